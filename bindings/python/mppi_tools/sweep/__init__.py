"""Sweeps on Dask: tasks (dicts of settings) -> figures, one table row each (docs/TUNING.md)."""
from .adapters import ClosedLoop, EvidenceCase, FitCommand, SimProcess, make_adapter  # noqa: F401
from .cluster import close_client, open_client  # noqa: F401
from .keys import task_key  # noqa: F401
from .runner import run_sweep  # noqa: F401
from .table import ResultTable, figure_columns  # noqa: F401
