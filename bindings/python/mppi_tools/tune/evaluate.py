"""The held-out evaluation: a tuned run file against a baseline (mppi-sim's defaults on the same
model and plant) on seeds and tracks, each an mppi-sim process (`mppi-sim --config FILE`) run as a
sweep task; a table and a Markdown comparison."""
import math
import os

from ..sweep.adapters import SimProcess
from ..sweep.runner import run_sweep


def tasks(run_file, baseline, tracks, seeds, laps):
    out = []
    for setup, settings in (('baseline', dict(baseline)), ('tuned', {'config': run_file})):
        for track in tracks:
            for seed in seeds:
                out.append({**settings, 'setup': setup, 'track': track, 'seed': seed, 'laps': laps, 'threads': 1})
    return out


class _Labelled(SimProcess):
    """SimProcess that ignores the `setup` label (it only names the row)."""
    kind = 'sim_process'

    def __call__(self, settings):
        return super().__call__({k: v for k, v in settings.items() if k != 'setup'})


def evaluate(run_file, baseline, tracks, seeds, laps, out_dir, client=None, bin_dir=None):
    adapter = _Labelled(os.path.join(out_dir, 'runs'), bin_dir)
    table, failures = run_sweep(adapter, tasks(run_file, baseline, tracks, seeds, laps),
                                os.path.join(out_dir, 'heldout.csv'), client)
    return table.frame(), failures


def _mean(values):
    values = [v for v in values if v is not None and math.isfinite(v)]
    return sum(values) / len(values) if values else float('nan')


def comparison(frame, tracks, run_file, baseline_text):
    """Markdown: per track and seed, the mean lap time and incidents of baseline and tuned."""
    import json
    lines = [f'Tuned: `{run_file}`. Baseline: mppi-sim defaults with `{baseline_text}`.', '',
             '| track | seed | baseline lap [s] | tuned lap [s] | change | baseline crashes / stalls | '
             'tuned crashes / stalls |', '|---|---|---|---|---|---|---|']
    verdicts = []
    for track in tracks:
        rows = frame[frame['track'] == track]
        per_setup = {}
        for setup in ('baseline', 'tuned'):
            laps_all, incidents = [], [0, 0]
            for _, r in rows[rows['setup'] == setup].sort_values('seed').iterrows():
                laps_all += json.loads(r['lap_times_s'])
                incidents[0] += int(r['crashes'])
                incidents[1] += int(r['stalls']) + (0 if str(r['finished']) == 'True' else 1)
            per_setup[setup] = (_mean(laps_all), incidents)
        for seed in sorted(set(rows['seed'])):
            b = rows[(rows['setup'] == 'baseline') & (rows['seed'] == seed)].iloc[0]
            t = rows[(rows['setup'] == 'tuned') & (rows['seed'] == seed)].iloc[0]
            change = t['mean_lap_s'] / b['mean_lap_s'] - 1
            lines.append(f'| {track} | {seed} | {b["mean_lap_s"]:.2f} | {t["mean_lap_s"]:.2f} | {100 * change:+.1f} % | '
                         f'{b["crashes"]} / {b["stalls"]} | {t["crashes"]} / {t["stalls"]} |')
        (bl, bi), (tl, ti) = per_setup['baseline'], per_setup['tuned']
        change = tl / bl - 1
        lines.append(f'| **{track}** | all | **{bl:.2f}** | **{tl:.2f}** | **{100 * change:+.1f} %** | '
                     f'**{bi[0]} / {bi[1]}** | **{ti[0]} / {ti[1]}** |')
        verdicts.append((track, change, ti))
    lines.append('')
    for track, change, ti in verdicts:
        ok = change <= -0.05 and ti == [0, 0]
        lines.append(f'- {track}: mean lap {100 * change:+.1f} %, tuned {ti[0]} crashes, {ti[1]} stalls or unfinished '
                     f'runs: {"**>= 5 % faster with 0 crashes**" if ok else "**not >= 5 % faster with 0 crashes**"}')
    return '\n'.join(lines) + '\n'
