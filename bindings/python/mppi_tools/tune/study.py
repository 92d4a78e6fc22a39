"""The study: Optuna, its trials run as Dask tasks, its state in an RDB storage every worker
reaches (a SQLite file on one machine; PostgreSQL for several: docs/TUNING.md). Each task
loads the study, asks for a trial, drives the evaluation's runs and tells the result."""
import time

from ..errors import ToolError
from ..sweep.adapters import ClosedLoop
from . import objective, space


def storage_for(url):
    import optuna
    if not ('://' in url):
        raise ToolError(f'--storage {url!r}: expected an SQLAlchemy URL, e.g. sqlite:///tune.db or '
                        f'postgresql://user:password@host/db')
    kwargs = {'connect_args': {'timeout': 120}} if url.startswith('sqlite') else {}
    try:
        return optuna.storages.RDBStorage(url, engine_kwargs=kwargs)
    except Exception as e:  # SQLAlchemy's errors: a missing driver, an unreachable server
        raise ToolError(f'--storage {url}: cannot open the study storage ({type(e).__name__}: {e})') from None


def create(url, name, seed):
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna.create_study(study_name=name, storage=storage_for(url), direction='minimize', load_if_exists=True,
                               sampler=optuna.samplers.TPESampler(seed=seed, n_startup_trials=10))


def enqueue_defaults(study, params):
    """The first trial: mppi-sim's defaults (where a parameter has one in range)."""
    values = {}
    for p in params:
        if p.default is None:
            continue
        if p.kind == 'choice' and p.default in p.choices or p.kind != 'choice' and p.low <= p.default <= p.high:
            values[p.name] = p.default
    if values and not study.trials:
        study.enqueue_trial(values)


def run_trial(url, name, params, fixed, evaluation, seed):
    """One trial (a Dask task): ask, run, tell. Returns its record."""
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.load_study(study_name=name, storage=storage_for(url),
                              sampler=optuna.samplers.TPESampler(seed=seed, n_startup_trials=10))
    trial = study.ask()
    start = time.monotonic()
    try:
        settings, values = space.suggest(trial, params, fixed)
        run = ClosedLoop()
        figures = [run(s) for s in evaluation.runs(settings)]
    except Exception as e:
        study.tell(trial, state=optuna.trial.TrialState.FAIL)
        return {'number': trial.number, 'error': f'{type(e).__name__}: {e}'}
    value, feasible, incidents = objective.score(figures)
    for key, v in (('settings', settings), ('values', values), ('feasible', feasible), ('incidents', incidents),
                   ('mean_lap_s', [f['mean_lap_s'] for f in figures]),
                   ('lap_over_limit', [f['mean_lap_over_limit'] for f in figures]),
                   ('wall_s', round(time.monotonic() - start, 1))):
        trial.set_user_attr(key, v)
    study.tell(trial, value)
    return {'number': trial.number, 'value': value, 'feasible': feasible, 'values': values}
