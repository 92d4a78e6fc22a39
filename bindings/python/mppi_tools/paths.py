"""Where the repository, its data and the built programs are."""
import os

from .errors import ToolError

REPO_ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..'))

# Environment variables that name one program each (set by ctest), else <bin dir>/<name>.
_PROGRAM_ENV = {'mppi-sim': 'MPPI_SIM_EXE', 'mppi-fit': 'MPPI_FIT_EXE', 'mppi-plot': 'MPPI_PLOT_EXE'}


def bin_dir():
    """$MPPI_BIN_DIR, else the source tree's build/bin."""
    return os.environ.get('MPPI_BIN_DIR') or os.path.join(REPO_ROOT, 'build', 'bin')


def program(name, directory=None):
    """The absolute path of a built program (mppi-sim, mppi-fit, mppi-plot); ToolError if it is not there."""
    explicit = os.environ.get(_PROGRAM_ENV.get(name, ''), '') if directory is None else ''
    path = explicit or os.path.join(os.path.abspath(directory or bin_dir()), name)
    if not os.access(path, os.X_OK):
        raise ToolError(f'{name} not found at {path}: build it (cmake --build build --target {name}), '
                        f'or pass its folder (--bin DIR / $MPPI_BIN_DIR)')
    return path
