"""Where the tasks of a sweep run: a LocalCluster on this machine, or the scheduler of a cluster
started by hand (dask-scheduler on one machine, dask-worker ADDRESS on each of the others)."""
import logging
import re

from ..errors import ToolError

_ADDRESS = re.compile(r'^(tcp|tls|inproc|ucx)://[^\s:/]+(:\d+)?$|^[^\s:/]+:\d+$')


def check_address(address):
    """The scheduler address as Dask takes it; ToolError for one that is not host:port or tcp://host:port."""
    if not _ADDRESS.match(address):
        raise ToolError(f'--scheduler {address!r}: expected tcp://HOST:PORT (as dask-scheduler prints it), e.g. '
                        f'tcp://10.0.0.5:8786')
    return address if '://' in address else 'tcp://' + address


def open_client(scheduler=None, workers=2, timeout_s=10):
    """A dask.distributed Client: on the scheduler at `scheduler`, or on a new LocalCluster of
    `workers` processes with one thread each (every task is one single-threaded run). Prints the
    dashboard's address."""
    from distributed import Client, LocalCluster
    if scheduler:
        address = check_address(scheduler)
        try:
            client = Client(address, timeout=f'{timeout_s}s')
        except (OSError, TimeoutError) as e:
            raise ToolError(f'cannot reach the Dask scheduler at {address} ({e}); start it with `dask-scheduler` '
                            f'and workers with `dask-worker {address}`') from e
        where = f'scheduler {address}, {len(client.scheduler_info()["workers"])} workers'
    else:
        if workers < 1:
            raise ToolError(f'--workers {workers}: a LocalCluster needs at least 1 worker')
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=':0',
                               silence_logs=logging.ERROR)
        client = Client(cluster)
        where = f'LocalCluster of {workers} worker processes x 1 thread'
    print(f'[dask] {where}; dashboard: {dashboard_text(client)}', flush=True)
    return client


def dashboard_text(client):
    link = client.dashboard_link
    try:
        import bokeh  # noqa: F401  (the dashboard's web pages need it)
    except ImportError:
        return f'{link} (not served: the dashboard needs bokeh, which is not installed)'
    return link


def close_client(client):
    """Closes the client and a LocalCluster it started."""
    cluster = getattr(client, 'cluster', None)
    # The progress bar's feed on the scheduler is cancelled as it closes; that is not an error.
    logging.getLogger('distributed.core').setLevel(logging.CRITICAL)
    client.close()
    if cluster is not None:
        cluster.close()
