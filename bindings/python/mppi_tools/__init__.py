"""Pure-Python tools around the mppi programs and module: sweeps on Dask (mppi_tools.sweep) and
the controller's tuner on Optuna (mppi_tools.tune). docs/TUNING.md."""
