"""mppi-sweep and mppi-tune through a cluster started by hand on loopback: a dask-scheduler and
two dask-worker processes (one single-threaded worker each), reached with --scheduler ADDRESS.

- A grid of short closed-loop runs gives the table of the serial run, every figure equal; a 4-trial
  study records its 4 trials and writes a run file with the best trial's settings.
- A worker killed (SIGKILL, with its nanny) in the middle of a sweep loses no result: the scheduler
  sends its tasks to the other worker and the table has every task, figures equal to the serial run's.

Every process is started in a session of its own and its group is stopped in a finally block."""
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import pandas as pd
import pytest
import yaml

pytest.importorskip('distributed')
pytest.importorskip('optuna')
mppi = pytest.importorskip('mppi')

import mppi_tools  # noqa: E402
from mppi_tools.sweep import ClosedLoop, close_client, open_client, run_sweep  # noqa: E402
from mppi_tools.sweep.cli import main as sweep_main  # noqa: E402
from mppi_tools.sweep.table import figure_columns  # noqa: E402
from mppi_tools.tune.cli import main as tune_main  # noqa: E402

START_S = 60  # the scheduler and each worker must be up within this


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class Loopback:
    """dask-scheduler on 127.0.0.1:PORT (no dashboard) and `workers` dask-worker processes
    (--nworkers 1 --nthreads 1), each a process group of its own; stopped on exit."""

    def __init__(self, folder, workers=2):
        self.folder, self.n_workers = str(folder), workers
        os.makedirs(self.folder, exist_ok=True)
        self.port = free_port()
        self.address = f'tcp://127.0.0.1:{self.port}'
        self.procs = {}  # name -> Popen
        package = os.path.dirname(os.path.dirname(os.path.abspath(mppi_tools.__file__)))
        module = os.path.dirname(os.path.abspath(mppi.__file__))
        self.env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            [package, module] + [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))

    def _start(self, name, args):
        log = open(os.path.join(self.folder, f'{name}.log'), 'w')
        self.procs[name] = subprocess.Popen([sys.executable, '-m', *args], stdout=log, stderr=subprocess.STDOUT,
                                            env=self.env, cwd=self.folder, start_new_session=True)
        log.close()

    def logs(self):
        text = []
        for name in self.procs:
            with open(os.path.join(self.folder, f'{name}.log')) as f:
                text.append(f'--- {name}.log (last lines)\n' + ''.join(f.readlines()[-15:]))
        return '\n'.join(text)

    def __enter__(self):
        try:
            self._start('scheduler', ['distributed.cli.dask_scheduler', '--host', '127.0.0.1', '--port',
                                      str(self.port), '--no-dashboard'])
            deadline = time.monotonic() + START_S
            while True:
                assert self.procs['scheduler'].poll() is None, f'dask-scheduler exited\n{self.logs()}'
                try:
                    socket.create_connection(('127.0.0.1', self.port), timeout=1).close()
                    break
                except OSError:
                    assert time.monotonic() < deadline, f'dask-scheduler not listening after {START_S} s\n{self.logs()}'
                    time.sleep(0.2)
            for i in range(self.n_workers):
                self._start(f'worker{i}', ['distributed.cli.dask_worker', self.address, '--nworkers', '1',
                                           '--nthreads', '1', '--no-dashboard', '--death-timeout', '30'])
            from distributed import Client
            with Client(self.address, timeout='20s') as client:
                try:
                    client.wait_for_workers(self.n_workers, timeout=START_S)
                except TimeoutError:
                    raise AssertionError(f'{self.n_workers} workers not up after {START_S} s\n{self.logs()}') from None
                self.worker_pids = client.run(os.getpid)  # address -> the worker's process
            return self
        except BaseException:
            self.stop()
            raise

    def kill_worker(self, address):
        """SIGKILL to the process group (nanny and worker) of the worker at address."""
        group = os.getpgid(self.worker_pids[address])
        assert group in {p.pid for n, p in self.procs.items() if n.startswith('worker')}, 'not a worker started here'
        os.killpg(group, signal.SIGKILL)

    def stop(self):
        for name, proc in reversed(list(self.procs.items())):
            if proc.poll() is None:
                try:
                    os.killpg(proc.pid, signal.SIGTERM)
                    proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait(timeout=10)
                except ProcessLookupError:
                    pass

    def __exit__(self, *exc):
        self.stop()


def figures_text(frame):
    """The table's settings and figures (not how the tasks ran), sorted by key, as CSV text."""
    frame = frame.astype(str).sort_values('key')
    return frame[figure_columns(frame)].to_csv(index=False)


def read_table(path):
    return pd.read_csv(path, dtype=str, keep_default_na=False)


def short_runs(seeds, speeds, samples=256, horizon=50):
    return [{'track': 'gazebo', 'model': 'single-track', 'plant': 'single-track', 'laps': 1, 'samples': samples,
             'horizon': horizon, 'threads': 1, 'seed': seed, 'speed': speed} for seed in seeds for speed in speeds]


def test_a_sweep_and_a_study_on_dask_scheduler_and_workers(tmp_path):
    tasks = short_runs(seeds=(1, 2), speeds=(7, 8))
    serial, failures = run_sweep(ClosedLoop(), tasks, str(tmp_path / 'serial.csv'))
    assert not failures
    grid = tmp_path / 'grid.yaml'
    grid.write_text(yaml.safe_dump({'kind': 'closed_loop', 'base': {k: v for k, v in tasks[0].items()
                                                                    if k not in ('seed', 'speed')},
                                    'grid': {'seed': [1, 2], 'speed': [7, 8]}}))
    with Loopback(tmp_path / 'cluster', workers=2) as cluster:
        rc = sweep_main(['grid', str(grid), '--scheduler', cluster.address, '--out', str(tmp_path / 'sweep')])
        assert rc == 0, cluster.logs()
        rc = tune_main(['run', '--scheduler', cluster.address, '--trials', '4', '--tracks', 'gazebo', '--seeds', '1',
                        '--laps', '1', '--params', 'speed,track-weight', '--range', 'speed=6:7', '--fixed',
                        'samples=256', '--fixed', 'horizon=50', '--study', 'loopback', '--out', str(tmp_path / 'tune')])
        assert rc == 0, cluster.logs()
        workers = set(cluster.worker_pids)
    table = read_table(tmp_path / 'sweep' / 'sweep.csv')
    assert len(table) == 4 and (table['laps_completed'] == '1').all()
    assert set(table['worker']) <= workers  # ran in the dask-worker processes
    assert figures_text(table) == figures_text(serial.frame())

    import optuna
    study = optuna.load_study(study_name='loopback', storage=f'sqlite:///{tmp_path / "tune" / "study.db"}')
    assert [t.state.name for t in study.trials] == ['COMPLETE'] * 4
    trials = pd.read_csv(tmp_path / 'tune' / 'trials.csv')
    assert sorted(trials['number']) == [0, 1, 2, 3] and trials['feasible'].all()
    assert trials['param.speed'].between(6, 7).all()
    best = trials.sort_values(['value', 'number']).iloc[0]
    assert best['value'] == pytest.approx(study.best_value)
    with open(tmp_path / 'tune' / 'best.yaml') as f:
        run_file = yaml.safe_load(f)
    assert run_file['speed'] == best['param.speed'] == json.loads(best['settings'])['speed']
    assert run_file['samples'] == 256 and run_file['horizon'] == 50 and run_file['model'] == 'single-track'


def test_a_worker_killed_in_a_sweep_loses_no_result(tmp_path):
    tasks = short_runs(seeds=(1, 2, 3), speeds=(7, 8), samples=1024, horizon=100)  # 6 runs of a few seconds
    serial, failures = run_sweep(ClosedLoop(), tasks, str(tmp_path / 'serial.csv'))
    assert not failures
    path = tmp_path / 'dask.csv'
    with Loopback(tmp_path / 'cluster', workers=2) as cluster:
        client = open_client(cluster.address)
        try:
            outcome = {}
            sweep = threading.Thread(target=lambda: outcome.update(
                zip(('table', 'failures'), run_sweep(ClosedLoop(), tasks, str(path), client))), daemon=True)
            sweep.start()
            deadline = time.monotonic() + 60
            while not (path.exists() and len(read_table(path)) >= 1):
                assert sweep.is_alive() and time.monotonic() < deadline, 'no first result'
                time.sleep(0.05)
            # A worker with a task in hand; its tasks not finished yet are lost with it.
            processing = {w: keys for w, keys in client.processing().items() if keys}
            assert processing, 'every task finished before a worker could be killed'
            victim = sorted(processing)[0]
            lost = {k.split('-', 1)[1] for k in processing[victim]}
            cluster.kill_worker(victim)
            sweep.join(timeout=90)
            assert not sweep.is_alive(), 'the sweep did not end after a worker was killed'
        finally:
            close_client(client)
    assert not outcome['failures'], outcome['failures']
    table = read_table(path)
    assert sorted(table['key']) == sorted(serial.frame()['key'])  # every task, once
    assert figures_text(table) == figures_text(serial.frame())
    survivor = (set(cluster.worker_pids) - {victim}).pop()
    rerun = table[table['key'].isin(lost) & (table['worker'] != victim)]
    assert len(rerun) >= 1 and (rerun['worker'] == survivor).all()  # the lost tasks ran on the other worker
