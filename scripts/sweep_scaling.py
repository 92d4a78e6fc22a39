#!/usr/bin/python3
"""Wall time of sweeps against the number of Dask workers (docs/TUNING.md, "What workers
buy"): a subset of the robustness benchmark (scripts/robustness_benchmark.py --dask), a subset
of the evidence grid (mppi-sweep evidence) and a grid of closed-loop runs (mppi-sweep grid, kind
closed_loop, --threads 1 each), each from empty folders on a LocalCluster of 1, then 2, ...
workers (`serial`: mppi-sweep --serial, no Dask); the tables are checked equal across worker
counts.

    /usr/bin/python3 scripts/sweep_scaling.py [--workers 1,2] [--sweeps robustness,evidence]
        [--evidence-cases 4] [--duration 30] [--closed-loop-runs 8] [--laps 4]
        [--out results/sweep_scaling] [--report docs/results/tuning] [--report-name sweep_scaling]

    e.g. --sweeps closed_loop --workers serial,2 --report-name closed_loop_scaling
"""
import argparse
import csv
import os
import platform
import shutil
import subprocess
import sys
import time

import pandas as pd
import yaml

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
sys.path.insert(0, os.path.join(ROOT, 'bindings', 'python'))
from mppi_tools.sweep.table import figure_columns  # noqa: E402

ROBUSTNESS = ['--quick', '--variants', 'plain,ess_act', '--plants', 'matched,network']


def timed(command):
    start = time.monotonic()
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f'{" ".join(command)} failed ({done.returncode}):\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}')
    return time.monotonic() - start


def figures(table):
    """The table's settings and figures without the run folder (it names the worker count's folder)
    and the key (a hash that includes it)."""
    frame = pd.read_csv(table, dtype=str, keep_default_na=False)
    columns = [c for c in figure_columns(frame) if c not in ('key', 'out')]
    return frame[columns].sort_values(columns).to_csv(index=False)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--workers', default='1,2')
    parser.add_argument('--evidence-cases', type=int, default=4, help='the first N cases of the reduced grid')
    parser.add_argument('--duration', type=float, default=30, help='evidence recording length [s]')
    parser.add_argument('--sweeps', default='robustness,evidence', help='of robustness, evidence, closed_loop')
    parser.add_argument('--closed-loop-runs', type=int, default=8, help='closed_loop: runs (seeds 1..N)')
    parser.add_argument('--laps', type=int, default=4, help='closed_loop: oval laps per run')
    parser.add_argument('--out', default='results/sweep_scaling')
    parser.add_argument('--report', default='docs/results/tuning')
    parser.add_argument('--report-name', default='sweep_scaling', help='REPORT/NAME.md and NAME.csv')
    args = parser.parse_args()
    os.chdir(ROOT)
    sweeps = args.sweeps.split(',')
    unknown = [s for s in sweeps if s not in ('robustness', 'evidence', 'closed_loop')]
    if unknown:
        sys.exit(f'--sweeps: unknown {unknown}; known: robustness, evidence, closed_loop')
    load_before = f'{os.getloadavg()[0]:.2f}'
    rows, tables = [], {}
    for workers in [w if w == 'serial' else int(w) for w in args.workers.split(',')]:
        where = ['--serial'] if workers == 'serial' else ['--workers', str(workers)]
        for sweep in sweeps:
            out = os.path.join(args.out, f'{sweep}_w{workers}')
            shutil.rmtree(out, ignore_errors=True)
            if sweep == 'closed_loop':
                os.makedirs(out)
                grid = os.path.join(out, 'grid.yaml')
                with open(grid, 'w') as f:
                    yaml.safe_dump({'kind': 'closed_loop',
                                    'base': {'track': 'gazebo', 'model': 'single-track', 'plant': 'single-track',
                                             'laps': args.laps, 'threads': 1},
                                    'grid': {'seed': list(range(1, args.closed_loop_runs + 1))}}, f)
                command = [sys.executable, 'bindings/python/mppi-sweep', 'grid', grid, *where, '--out', out]
                what = (f'closed loop, {args.closed_loop_runs} runs (seeds), {args.laps} oval laps, mppi-sim defaults, '
                        f'--threads 1')
            elif workers == 'serial':
                sys.exit(f'--workers serial: only for the closed_loop sweep, not {sweep}')
            elif sweep == 'robustness':
                command = [sys.executable, 'scripts/robustness_benchmark.py', *ROBUSTNESS, '--dask', '--workers',
                           str(workers), '--out', out, '--report', out]
                what = 'robustness --quick, variants plain+ess_act x plants matched+network (4 runs, 2 oval laps)'
            else:
                command = [sys.executable, 'bindings/python/mppi-sweep', 'evidence', '--reduced', '--first',
                           str(args.evidence_cases), '--duration', f'{args.duration:g}', '--workers', str(workers),
                           '--out', out]
                what = (f'evidence grid (reduced), first {args.evidence_cases} cases, {args.duration:g}-s '
                        f'recordings')
            seconds = timed(command)
            tables.setdefault(sweep, []).append(figures(os.path.join(out, 'sweep.csv')))
            task_s = pd.read_csv(os.path.join(out, 'sweep.csv'))['wall_s'].sum()
            rows.append({'sweep': sweep, 'what': what, 'workers': workers, 'wall_s': round(seconds, 1),
                         'task_wall_sum_s': round(task_s, 1)})
            print(f'{sweep}: {workers} workers {seconds:.1f} s', flush=True)
    same = {sweep: all(t == ts[0] for t in ts) for sweep, ts in tables.items()}
    os.makedirs(args.report, exist_ok=True)
    with open(os.path.join(args.report, f'{args.report_name}.csv'), 'w', newline='') as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = ['# Sweep wall time against Dask workers', '',
             'Generated by `scripts/sweep_scaling.py`; do not edit by hand.', '',
             f'Machine: {os.cpu_count()} cores ({platform.processor() or platform.machine()}), '
             f'LocalCluster, 1 thread per worker, each run single-threaded; shared with other work; '
             f'load average before: {load_before}, after: {os.getloadavg()[0]:.2f} (1 min).', '',
             'Sum of task wall times: each task from start to end in its worker; above the serial sum where the '
             'tasks ran slower side by side (cores shared with each other or with other work).', '',
             '| sweep | workers | wall time [s] | speed-up | sum of task wall times [s] | tables equal across worker '
             'counts |', '|---|---|---|---|---|---|']
    for r in rows:
        base = next(x['wall_s'] for x in rows if x['sweep'] == r['sweep'])
        lines.append(f'| {r["what"]} | {r["workers"]} | {r["wall_s"]:.1f} | {base / r["wall_s"]:.2f}x | '
                     f'{r["task_wall_sum_s"]:.1f} | '
                     f'{"yes" if same[r["sweep"]] else "**NO**"} |')
    with open(os.path.join(args.report, f'{args.report_name}.md'), 'w') as f:
        f.write('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0 if all(same.values()) else 1


if __name__ == '__main__':
    sys.exit(main())
