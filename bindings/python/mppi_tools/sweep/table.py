"""The results of a sweep on disk: one row per finished task (its key, settings and figures),
as CSV (or Parquet where pyarrow is installed). Rows are rewritten atomically after each task, so
a sweep cut short keeps what it finished."""
import json
import os

import pandas as pd

from ..errors import ToolError

# Columns that say how a task ran, not what it computed: they differ between runs of the same task
# (also every figure named wall_*, such as the optimizer's wall time per step).
RUN_COLUMNS = ('wall_s', 'worker')


def cell(value):
    """A value as one table cell: lists and dicts as JSON text."""
    return json.dumps(value, sort_keys=True) if isinstance(value, (list, tuple, dict)) else value


class ResultTable:
    def __init__(self, path):
        self.path = path
        if not (path.endswith('.csv') or path.endswith('.parquet')):
            raise ToolError(f'{path}: a result table is a .csv or .parquet file')
        self.rows = []
        if os.path.exists(path):
            frame = self._read()
            if 'key' not in frame.columns:
                raise ToolError(f'{path}: not a sweep table (no "key" column)')
            self.rows = frame.to_dict('records')

    def _read(self):
        if self.path.endswith('.parquet'):
            return pd.read_parquet(self.path)
        return pd.read_csv(self.path, dtype={'key': str}, keep_default_na=False, na_values=[''])

    def done_keys(self):
        return {row['key'] for row in self.rows}

    def add(self, row):
        self.rows.append({k: cell(v) for k, v in row.items()})
        self.save()

    def frame(self):
        """The rows sorted by key (the order tasks finished in does not show)."""
        rows = sorted(self.rows, key=lambda r: r['key'])
        columns = list(dict.fromkeys(c for r in rows for c in r))
        return pd.DataFrame(rows, columns=columns)

    def save(self):
        directory = os.path.dirname(os.path.abspath(self.path))
        os.makedirs(directory, exist_ok=True)
        tmp = self.path + '.tmp'
        frame = self.frame()
        if self.path.endswith('.parquet'):
            try:
                frame.to_parquet(tmp, index=False)
            except ImportError as e:
                raise ToolError(f'{self.path}: Parquet needs pyarrow ({e}); write a .csv table instead') from e
        else:
            frame.to_csv(tmp, index=False)
        os.replace(tmp, self.path)


def figure_columns(frame):
    """The columns of a table that hold what the tasks computed (not how they ran)."""
    return [c for c in frame.columns if c not in RUN_COLUMNS and not c.startswith('wall_')]
