"""The launchers' common start: the mppi module on the path (build/python, or $PYTHONPATH), then
the command's main."""
import importlib
import os
import sys

from .paths import REPO_ROOT


def main_of(module_name):
    module_dir = os.environ.get('MPPI_PYTHON_DIR') or os.path.join(REPO_ROOT, 'build', 'python')
    if os.path.isdir(module_dir) and module_dir not in sys.path:
        sys.path.append(module_dir)
    # Dask's worker processes start from this interpreter's sys.path only where they are spawned
    # here (LocalCluster); PYTHONPATH carries it to dask-worker processes started by hand.
    os.environ['PYTHONPATH'] = os.pathsep.join(
        p for p in [os.path.dirname(os.path.dirname(os.path.abspath(__file__))), module_dir,
                    os.environ.get('PYTHONPATH', '')] if p)
    return importlib.import_module(module_name).main()
