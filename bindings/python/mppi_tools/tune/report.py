"""What a study leaves on disk: trials.csv (every trial's parameters, value, feasibility),
history.json/.png and importance.json/.png (mppi-plot), importance.csv, and the best settings as
an mppi-sim run file."""
import json
import math
import os

import pandas as pd

from .. import runfile
from . import figures, importance, objective


def trial_records(study):
    import optuna
    rows = []
    for t in study.trials:
        if t.state != optuna.trial.TrialState.COMPLETE:
            continue
        rows.append({'number': t.number, 'value': t.value, 'feasible': bool(t.user_attrs.get('feasible')),
                     'incidents': t.user_attrs.get('incidents'), 'wall_s': t.user_attrs.get('wall_s'),
                     # the values the trial ran (rounded as written to the run file), not Optuna's raw draws
                     **{f'param.{k}': v for k, v in t.user_attrs.get('values', t.params).items()},
                     'lap_over_limit': json.dumps(t.user_attrs.get('lap_over_limit')),
                     'settings': json.dumps(t.user_attrs.get('settings'), sort_keys=True)})
    return rows


def best_trial(study):
    """The feasible trial with the lowest value (None if none is feasible)."""
    feasible = [r for r in trial_records(study) if r['feasible']]
    return min(feasible, key=lambda r: (r['value'], r['number'])) if feasible else None


def write_run_file(study, path, header):
    best = best_trial(study)
    if best is None:
        return None
    settings = json.loads(best['settings'])
    for per_run in ('track', 'seed', 'laps', 'threads'):
        settings.pop(per_run, None)
    comment = (f'{header}\nBest trial {best["number"]}: mean lap / limit lap {best["value"]:.4f} over the '
               f'evaluation, 0 crashes, 0 stalls.\nmppi-sim --config {path} [--track T --seed S --laps N]')
    runfile.write_run_file(path, settings, comment=comment)
    return best


def write_all(study, out_dir, bin_dir=None):
    """trials.csv, history / importance JSON + PNG; returns (records, importance dict)."""
    os.makedirs(out_dir, exist_ok=True)
    records = trial_records(study)
    pd.DataFrame(records).to_csv(os.path.join(out_dir, 'trials.csv'), index=False)
    feasible = [r for r in records if r['feasible']]
    top = max([r['value'] for r in feasible] or [2.0])
    history = [(r['number'], r['value'], r['feasible']) for r in records]
    figures.draw(figures.single(figures.history_panel(history, top + 0.1 * max(top - 1, 0.1)),
                                f'{study.study_name}: mean lap over limit lap per trial '
                                f'(infeasible: value {objective.INFEASIBLE:g} + incidents, drawn at the top)'),
                 os.path.join(out_dir, 'history.json'), os.path.join(out_dir, 'history.png'), bin_dir)
    trials = [({k[len('param.'):]: v for k, v in r.items() if k.startswith('param.') and not _missing(v)}, r['value'])
              for r in feasible]
    imp = importance.importances(trials)
    pd.DataFrame({'parameter': list(imp), 'eta2': list(imp.values())}).to_csv(
        os.path.join(out_dir, 'importance.csv'), index=False)
    if imp:
        figures.draw(figures.single(figures.importance_panel(imp),
                                    f'{study.study_name}: parameter importances (feasible trials)',
                                    width_px=max(900, 150 + 8 * len(', '.join(f'{i} {n}' for i, n in enumerate(imp))))),
                     os.path.join(out_dir, 'importance.json'), os.path.join(out_dir, 'importance.png'), bin_dir)
    return records, imp


def _missing(v):
    return v is None or isinstance(v, float) and math.isnan(v)
