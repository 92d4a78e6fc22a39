"""A sweep: tasks (dicts of settings) through one adapter (settings -> dict of figures), on a
Dask cluster or serially in this process, into a ResultTable. Tasks whose key the table already
holds are not run again; a task that fails is reported and left out of the table (a rerun tries
it again)."""
import os
import socket
import threading
import time
import traceback

from ..errors import ToolError
from .keys import task_key
from .table import ResultTable


def run_task(adapter, key, settings):
    """One task: the table row (key, kind, settings, figures, wall_s, worker), or {'key', 'error'}."""
    start = time.monotonic()
    try:
        figures = adapter(settings)
    except Exception as e:  # reported with the task's key; the sweep goes on
        return {'key': key, 'error': f'{type(e).__name__}: {e}', 'traceback': traceback.format_exc()}
    clash = sorted(set(figures) & (set(settings) | {'key', 'kind', 'wall_s', 'worker'}))
    if clash:
        return {'key': key, 'error': f'{adapter.kind}: figures {clash} have the names of settings'}
    try:
        from distributed import get_worker
        worker = get_worker().address
    except (ImportError, ValueError):
        worker = f'serial@{socket.gethostname()}'
    row = {'key': key, 'kind': adapter.kind}
    row.update({k: settings[k] for k in sorted(settings)})
    row.update({k: figures[k] for k in sorted(figures)})
    row.update({'wall_s': round(time.monotonic() - start, 3), 'worker': worker})
    return row


def plan(adapter, tasks):
    """[(key, settings)] in the given order; ToolError for two tasks with the same settings."""
    keyed, seen = [], {}
    for i, settings in enumerate(tasks):
        if not isinstance(settings, dict):
            raise ToolError(f'task {i}: settings must be a dict, got {type(settings).__name__}')
        key = task_key(adapter.kind, settings)
        if key in seen:
            raise ToolError(f'tasks {seen[key]} and {i} have the same settings ({settings})')
        seen[key] = i
        keyed.append((key, settings))
    return keyed


def collect(future, key):
    """A finished future's result. A task that raised returns its error itself (run_task); one that
    Dask gave up on (its workers died while running it more often than the scheduler's
    distributed.scheduler.allowed-failures; a worker lost once only sends its tasks to the other
    workers) is reported like a failed task, so the sweep goes on and a rerun tries it again."""
    try:
        return future.result()
    except Exception as e:  # KilledWorker, CancelledError
        return {'key': key, 'error': f'{type(e).__name__} (Dask lost the task): {e}'}


def _progress_in_background(futures):
    """Dask's text progress bar in a thread, while the caller collects the results as they come."""
    from distributed import progress
    thread = threading.Thread(target=progress, args=(futures,), kwargs={'notebook': False, 'interval': '2s'}, daemon=True)
    thread.start()
    return thread


def run_sweep(adapter, tasks, table_path, client=None, log=print):
    """Runs the tasks not yet in the table at table_path; returns (ResultTable, failures).
    client: a dask.distributed Client, or None to run them one after another here."""
    table = ResultTable(table_path)
    keyed = plan(adapter, tasks)
    done = table.done_keys()
    todo = [(k, s) for k, s in keyed if k not in done]
    log(f'[sweep] {adapter.kind}: {len(keyed)} tasks, {len(keyed) - len(todo)} done before, {len(todo)} to run '
        f'-> {table_path}')
    failures = []

    def record(result):
        if 'error' in result:
            failures.append(result)
            log(f'[sweep] task {result["key"]} FAILED: {result["error"]}')
        else:
            table.add(result)

    start = time.monotonic()
    if client is None:
        for n, (key, settings) in enumerate(todo, 1):
            record(run_task(adapter, key, settings))
            log(f'[sweep] {n}/{len(todo)} ({time.monotonic() - start:.0f} s)')
    elif todo:
        from distributed import as_completed
        futures = client.map(run_task, [adapter] * len(todo), [k for k, _ in todo], [s for _, s in todo],
                             key=[f'{adapter.kind}-{k}' for k, _ in todo], pure=False)
        bar = _progress_in_background(futures)
        keys = {future.key: key for future, (key, _) in zip(futures, todo)}
        for future in as_completed(futures):
            record(collect(future, keys[future.key]))
        bar.join(timeout=10)  # the bar ends with its futures; closing the client under it would cancel it
        print(flush=True)
    if todo:
        log(f'[sweep] {len(todo) - len(failures)} ran, {len(failures)} failed in {time.monotonic() - start:.1f} s'
            f'{"; rerun to retry them" if failures else ""}')
    return table, failures


def default_table(out_dir, name='sweep'):
    return os.path.join(out_dir, f'{name}.csv')
