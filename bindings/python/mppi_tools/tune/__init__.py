"""The controller's tuner on Optuna, trials on Dask (docs/TUNING.md)."""
