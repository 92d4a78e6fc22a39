"""Sweeps: the same tasks on a 2-worker LocalCluster and serially give the same table (bit for
bit on the figures); a rerun skips the tasks done; bad settings and addresses are refused by name."""
import os

import pandas as pd
import pytest

from mppi_tools.errors import ToolError
from mppi_tools.sweep import ClosedLoop, open_client, close_client, run_sweep, task_key
from mppi_tools.sweep.cluster import check_address
from mppi_tools.sweep.table import figure_columns

pytest.importorskip('distributed')
mppi = pytest.importorskip('mppi')

# Short closed-loop runs (one lap of the oval, small K and horizon, 1 thread): 2 seeds x 2 speeds.
TINY = [{'track': 'gazebo', 'model': 'single-track', 'plant': 'single-track', 'laps': 1, 'samples': 256,
         'horizon': 50, 'threads': 1, 'seed': seed, 'speed': speed} for seed in (1, 2) for speed in (7, 8)]


def figures_text(path):
    """The table without the columns that say how the tasks ran, as CSV text."""
    frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    return frame[figure_columns(frame)].to_csv(index=False)


def test_two_workers_give_the_serial_table(tmp_path):
    serial, failures = run_sweep(ClosedLoop(), TINY, str(tmp_path / 'serial.csv'), client=None)
    assert not failures
    client = open_client(workers=2)
    try:
        dask_table, failures = run_sweep(ClosedLoop(), TINY, str(tmp_path / 'dask.csv'), client)
        workers = set(dask_table.frame()['worker'])
    finally:
        close_client(client)
    assert not failures
    assert len(workers) >= 1 and all(w.startswith('tcp://') for w in workers)  # ran in the workers
    frame = serial.frame()
    assert len(frame) == len(TINY)
    # The runs differ from one another, so rows matched to the wrong task would show.
    assert frame['mean_speed_mps'].nunique() == len(TINY)
    assert (frame['laps_completed'] == 1).all()
    assert figures_text(tmp_path / 'dask.csv') == figures_text(tmp_path / 'serial.csv')


class Counting:
    """A task adapter that counts its calls in a file (the skip-done test's oracle)."""
    kind = 'counting'

    def __init__(self, log):
        self.log = log

    def __call__(self, settings):
        with open(self.log, 'a') as f:
            f.write(f'{settings["x"]}\n')
        if settings['x'] == 'fail':
            raise ValueError('asked to fail')
        return {'y': settings['x'] * 2}


def test_a_rerun_skips_the_tasks_done(tmp_path):
    log, table = str(tmp_path / 'calls.txt'), str(tmp_path / 'table.csv')
    run_sweep(Counting(log), [{'x': 1}, {'x': 2}], table)
    _, failures = run_sweep(Counting(log), [{'x': 2}, {'x': 1}, {'x': 3}, {'x': 'fail'}], table)
    with open(log) as f:
        calls = f.read().split()
    assert calls == ['1', '2', '3', 'fail']  # 1 and 2 not again; the failure is reported
    assert [f['error'] for f in failures] == ['ValueError: asked to fail']
    frame = pd.read_csv(table, dtype={'key': str})
    assert sorted(frame['x']) == [1, 2, 3] and sorted(frame['y']) == [2, 4, 6]
    assert set(frame['key']) == {task_key('counting', {'x': x}) for x in (1, 2, 3)}
    run_sweep(Counting(log), [{'x': 'fail'}], table)  # a failed task is tried again
    with open(log) as f:
        assert f.read().split().count('fail') == 2


def test_the_key_is_the_settings_not_their_order():
    assert task_key('k', {'a': 1, 'b': [1, 2]}) == task_key('k', {'b': [1, 2], 'a': 1})
    assert task_key('k', {'a': 1}) != task_key('k', {'a': 2}) != task_key('j', {'a': 2})


def test_two_tasks_with_the_same_settings_are_refused(tmp_path):
    with pytest.raises(ToolError, match='same settings'):
        run_sweep(Counting(str(tmp_path / 'c')), [{'x': 1}, {'x': 1}], str(tmp_path / 't.csv'))


def test_bad_scheduler_addresses_are_named():
    with pytest.raises(ToolError, match="--scheduler 'not an address'"):
        check_address('not an address')
    assert check_address('10.0.0.5:8786') == 'tcp://10.0.0.5:8786'
    with pytest.raises(ToolError, match='cannot reach the Dask scheduler at tcp://127.0.0.1:9'):
        open_client('tcp://127.0.0.1:9', timeout_s=2)


def test_unknown_settings_and_missing_programs_are_named(tmp_path):
    with pytest.raises(ToolError, match="setting 'no-such-flag'"):
        ClosedLoop().config({'no-such-flag': 1})
    with pytest.raises(ToolError, match="setting 'cost.wheel_weight'"):
        ClosedLoop().config({'cost.wheel_weight': 1})
    from mppi_tools.sweep import SimProcess
    with pytest.raises(ToolError, match=f'mppi-sim not found at {tmp_path}'):
        SimProcess(str(tmp_path), bin_dir=str(tmp_path))


def test_an_unknown_table_format_is_refused(tmp_path):
    with pytest.raises(ToolError, match='.csv or .parquet'):
        run_sweep(Counting(str(tmp_path / 'c')), [{'x': 1}], str(tmp_path / 'table.txt'))
