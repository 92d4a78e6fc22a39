"""The evidence grid as tasks: mppi-fit lists the grid's cases, a task runs one case by label,
and its figures are those of the same case in mppi-fit's own sweep (the oracle)."""
import json
import subprocess

import pytest

from mppi_tools import paths
from mppi_tools.errors import ToolError
from mppi_tools.sweep.adapters import EVIDENCE_FIGURES, EvidenceCase
from mppi_tools.sweep.evidence_grid import grid_flags, list_cases, tasks_for


def test_the_reduced_grid_lists_its_cases():
    labels = list_cases(grid_flags(reduced=True))
    assert len(labels) == len(set(labels)) == 45  # 19 effects x 2 sizes + 3 pairs + 4 effect-free
    assert labels[0] == 'steer_delay_small_s1'
    assert sum(label.startswith('none_clean_s') for label in labels) == 4
    assert sum(label.endswith('_pair_s1') for label in labels) == 3


def test_an_unknown_case_is_refused_by_name(tmp_path):
    with pytest.raises(ToolError, match='mppi-fit exited 2'):
        EvidenceCase(str(tmp_path))({'case': 'no_such_case_s1', 'reduced': True})
    with open(tmp_path / 'no_such_case_s1' / 'mppi_fit.log') as f:
        assert "'no_such_case_s1' is not a case of this grid" in f.read()


def test_a_case_task_gives_the_figures_of_mppi_fits_own_sweep(tmp_path):
    [task] = tasks_for(['steer_delay_small_s1'], reduced=True, duration=8)
    figures = EvidenceCase(str(tmp_path / 'tasks'))(task)
    oracle_dir = tmp_path / 'oracle'
    done = subprocess.run([paths.program('mppi-fit'), 'diagnose', 'sweep', '--generator', 'independent', '--effects',
                           'steer_delay', '--sizes', 'small', '--seeds', '1', '--pairs', '0', '--clean', '0',
                           '--duration', '8', '--out', str(oracle_dir)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    with open(oracle_dir / 'runs.jsonl') as f:
        oracle = json.loads(f.readline())
    assert oracle['label'] == 'steer_delay_small_s1' and not oracle.get('error')
    assert figures == {k: oracle[k] for k in EVIDENCE_FIGURES}
    assert figures['heldout_1s_nrmse_clean_before'] > 0
