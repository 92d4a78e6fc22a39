"""mppi_tools tests: the package from the source tree, the mppi module and programs from the build
(ctest sets PYTHONPATH and MPPI_BIN_DIR; see bindings/CMakeLists.txt)."""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
_build_python = os.path.join(HERE, '..', '..', '..', 'build', 'python')
if os.path.isdir(_build_python) and _build_python not in sys.path:
    sys.path.append(_build_python)
