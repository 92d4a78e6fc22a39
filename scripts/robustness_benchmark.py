#!/usr/bin/python3
"""The controller's robustness benchmark (docs/ROBUSTNESS.md): every controller variant
(data/config/robustness_variants.yaml) drives every plant row (the matched model, the network
on the single-track car, the actuated car and four mismatched cars, data/config/robustness/)
on the built-in tracks with mppi-sim; the runs' summary.json files are reduced to one cell per
(track group, plant, variant) and written as a Markdown table, a CSV and a figure.

    /usr/bin/python3 scripts/robustness_benchmark.py [--quick] [--variants a,b] [--plants x,y]
                                                     [--jobs N] [--out DIR] [--bin DIR]
                                                     [--dask [tcp://HOST:8786]] [--workers N]

With --dask the runs are Dask tasks (one mppi-sim process each, --threads 1): on a LocalCluster of
--workers processes, or on the scheduler named (a cluster of dask-scheduler / dask-worker; the
run folders must be on a file system every worker shares); their figures also go to
OUT/sweep.csv (docs/TUNING.md).

Runs whose summary.json exists are not run again: a rerun resumes, and one with more variants
or plants runs only the new cells. Debian's python3 with the standard library (numpy and
pandas are not needed); the figure is drawn by the project's mppi-plot.
"""
import argparse
import concurrent.futures
import csv
import json
import math
import os
import re
import subprocess
import sys
import time

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
VARIANTS_FILE = 'data/config/robustness_variants.yaml'
NETWORK = 'autorally-nn'
ACTUATED_PLANT = 'data/config/autorally_single_track_actuated.yaml'
MISMATCH_PLANTS = ['delay', 'grip', 'grade', 'payload']

# Plant rows: name -> mppi-sim flags of the controller model and the simulated car.
PLANT_ROWS = {
    'matched': ['--model', 'single-track', '--plant', 'single-track'],
    'network': ['--model', NETWORK, '--plant', 'single-track'],
    'actuated': ['--model', NETWORK, '--plant', 'corrected', '--plant-params', ACTUATED_PLANT],
}
for _name in MISMATCH_PLANTS:
    PLANT_ROWS[_name] = ['--model', NETWORK, '--plant', 'corrected', '--plant-params',
                         f'data/config/robustness/{_name}.yaml']

TARGET_SPEED_MPS = 8.0
# Track groups: (group, mppi-sim track, seeds, laps per run).
FULL_GROUPS = [('oval', 'gazebo', [1, 2, 3], 10), ('marietta', 'marietta', [1], 3), ('ccrf', 'ccrf', [1], 3)]
QUICK_GROUPS = [('oval', 'gazebo', [1], 2)]


# ---- the variants file ----------------------------------------------------------------------------
def split_flow_list(text, where):
    """The words of a YAML flow list '[a, "b c", d]' (no nesting)."""
    text = text.strip()
    if not (text.startswith('[') and text.endswith(']')):
        raise ValueError(f'{where}: expected a list [flag, value, ...], got {text!r}')
    words, word, quote = [], '', None
    for c in text[1:-1]:
        if quote:
            if c == quote:
                quote = None
            else:
                word += c
        elif c in '"\'':
            quote = c
        elif c == ',':
            words.append(word.strip())
            word = ''
        else:
            word += c
    if quote:
        raise ValueError(f'{where}: unclosed quote')
    if word.strip() or words:
        words.append(word.strip())
    if any(w == '' for w in words):
        raise ValueError(f'{where}: empty word in {text!r}')
    return words


def strip_comment(line):
    """The line without a '#' comment outside quotes."""
    quote = None
    for i, c in enumerate(line):
        if quote:
            quote = None if c == quote else quote
        elif c in '"\'':
            quote = c
        elif c == '#':
            return line[:i]
    return line


def read_variants(path):
    """Ordered {name: [flags]} from a .json object or a YAML file of `name: [flags]` lines."""
    with open(path) as f:
        text = f.read()
    if path.endswith('.json'):
        variants = json.loads(text)
        return {str(k): [str(w) for w in v] for k, v in variants.items()}
    variants = {}
    for number, raw in enumerate(text.splitlines(), 1):
        line = strip_comment(raw).strip()
        if not line:
            continue
        where = f'{path}:{number}'
        name, sep, rest = line.partition(':')
        if not sep or not name.strip():
            raise ValueError(f'{where}: expected `name: [flags]`')
        variants[name.strip()] = split_flow_list(rest, where)
    if not variants:
        raise ValueError(f'{path}: no variants')
    return variants


# ---- the runs -------------------------------------------------------------------------------------
class Run:
    def __init__(self, variant, flags, plant, group, track, seed, laps, out):
        self.variant, self.plant, self.group = variant, plant, group
        self.track, self.seed, self.laps = track, seed, laps
        self.variant_flags = flags
        self.dir = os.path.join(out, 'runs', variant, plant, f'{track}_seed{seed}_{laps}laps')

    @property
    def summary_path(self):
        return os.path.join(self.dir, 'summary.json')

    def command(self, binary, threads):
        return ([binary, '--track', self.track, *PLANT_ROWS[self.plant], '--speed', str(TARGET_SPEED_MPS),
                 '--laps', str(self.laps), '--seed', str(self.seed), '--threads', str(threads),
                 '--out', self.dir, '--quiet'] + self.variant_flags)

    def label(self):
        return f'{self.variant} / {self.plant} / {self.track} seed {self.seed}'


def plan_runs(variants, plants, groups, out):
    return [Run(v, flags, p, group, track, seed, laps, out)
            for v, flags in variants.items() for p in plants
            for group, track, seeds, laps in groups for seed in seeds]


def execute(run, binary, threads):
    """Runs mppi-sim; (run, seconds, error or None). mppi-sim exits 1 for a run that did not
    finish its laps, which still has a summary."""
    os.makedirs(run.dir, exist_ok=True)
    start = time.monotonic()
    with open(os.path.join(run.dir, 'mppi_sim.log'), 'w') as log:
        log.write(' '.join(run.command(binary, threads)) + '\n')
        log.flush()
        rc = subprocess.call(run.command(binary, threads), cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)
    seconds = time.monotonic() - start
    if not os.path.exists(run.summary_path):
        return run, seconds, f'mppi-sim exited {rc} without a summary (see {run.dir}/mppi_sim.log)'
    return run, seconds, None


def run_all_on_dask(runs, bin_dir, address, workers, out):
    """The runs not yet done as Dask tasks (mppi_tools.sweep, bindings/python); failures as run_all's."""
    sys.path.insert(0, os.path.join(ROOT, 'bindings', 'python'))
    from mppi_tools.runfile import flags_to_settings
    from mppi_tools.sweep import SimProcess, close_client, open_client, run_sweep
    todo = [r for r in runs if not os.path.exists(r.summary_path)]
    print(f'{len(runs)} runs, {len(runs) - len(todo)} done before, {len(todo)} to run (Dask tasks, --threads 1 each)',
          flush=True)
    if not todo:
        return []
    from mppi_tools.sweep import task_key
    tasks, run_of = [], {}
    for r in todo:
        settings = flags_to_settings(r.command('mppi-sim', 1)[1:])  # 'out' is the run's folder
        settings.pop('quiet', None)
        tasks.append(settings)
        run_of[task_key(SimProcess.kind, settings)] = r
    client = open_client(address, workers)
    try:
        _, failed = run_sweep(SimProcess(os.path.join(out, 'runs'), bin_dir), tasks, os.path.join(out, 'sweep.csv'),
                              client)
    finally:
        close_client(client)
    return [(run_of[f['key']], f['error']) for f in failed]


def format_duration(seconds):
    seconds = int(round(seconds))
    return f'{seconds // 3600}h{seconds % 3600 // 60:02d}m' if seconds >= 3600 else f'{seconds // 60}m{seconds % 60:02d}s'


def run_all(runs, binary, jobs):
    todo = [r for r in runs if not os.path.exists(r.summary_path)]
    threads = max(1, (os.cpu_count() or 1) // jobs)
    print(f'{len(runs)} runs, {len(runs) - len(todo)} done before, {len(todo)} to run '
          f'({jobs} at a time, --threads {threads} each)', flush=True)
    failures = []
    if not todo:
        return failures
    start = time.monotonic()
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(execute, r, binary, threads) for r in todo]
        for done, future in enumerate(concurrent.futures.as_completed(futures), 1):
            run, seconds, error = future.result()
            elapsed = time.monotonic() - start
            eta = elapsed / done * (len(todo) - done)
            status = f'FAILED: {error}' if error else 'ok'
            print(f'[{done}/{len(todo)}] {run.label()}: {seconds:.0f} s, {status}; '
                  f'elapsed {format_duration(elapsed)}, ETA {format_duration(eta)}', flush=True)
            if error:
                failures.append((run, error))
    return failures


# ---- the cells ------------------------------------------------------------------------------------
def mean(values):
    values = [v for v in values if v is not None and math.isfinite(v)]
    return sum(values) / len(values) if values else float('nan')


def finite(values):
    return [v for v in values if v is not None and math.isfinite(v)]


def reduce_cell(summaries, limit_lap_s=None, standing_limit_lap_s=None):
    """The figures of one cell from its runs' summaries; the lap ratios against limit_lap_s where
    given (the limit lap by collocation; lap 1, which starts from rest, against
    standing_limit_lap_s), else the runs' own lap_time_ratio (mppi-sim's default, QSS; lap 1 against
    its standing-start limit lap as well). mean_lap_over_limit is the mean lap time over the flying
    limit lap."""
    laps = [t for s in summaries for t in finite(s['lap_times_s'])]
    if limit_lap_s is None:
        ratios = [r for s in summaries for r in finite(s['lap_time_ratio'])]
        limits = finite([s['limit_lap_s'] for s in summaries])
        limit_lap_s = limits[0] if limits else float('nan')
    else:
        standing = standing_limit_lap_s if standing_limit_lap_s is not None else float('nan')
        ratios = finite([t / (standing if i == 0 else limit_lap_s)
                         for s in summaries for i, t in enumerate(s['lap_times_s'])]) if math.isfinite(limit_lap_s) else []
        limits = [limit_lap_s] if math.isfinite(limit_lap_s) else []
    return {
        'runs': len(summaries),
        'laps': len(laps),
        'finished_runs': sum(1 for s in summaries if s['finished']),
        'crashes': sum(s['crashes'] for s in summaries),
        'stalls': sum(s['stalls'] for s in summaries),
        'mean_speed_mps': mean([s['mean_speed_mps'] for s in summaries]),
        'mean_lap_s': mean(laps),
        'limit_lap_s': limit_lap_s,
        'mean_lap_over_limit': mean(laps) / limit_lap_s if laps and limits else float('nan'),
        'fastest_lap_over_limit': min(ratios) if ratios else float('nan'),
        'peak_slip_deg': max(math.degrees(s['peak_slip_angle_rad']) for s in summaries),
        'mean_abs_steer_step': mean([s.get('mean_abs_steer_step') for s in summaries]),
        'mean_abs_throttle_step': mean([s.get('mean_abs_throttle_step') for s in summaries]),
        'optimizer_ms_p50': mean([s['optimizer_ms_p50'] for s in summaries]),
        'optimizer_ms_p99': max(finite([s['optimizer_ms_p99'] for s in summaries]) or [float('nan')]),
    }


def reduce_cells(runs, limit_laps=None):
    """limit_laps: (track, plant) -> (flying, standing-start) limit lap [s] (collocation_limit_laps),
    or None for the runs' own."""
    grouped, track_of = {}, {}
    for run in runs:
        if os.path.exists(run.summary_path):
            with open(run.summary_path) as f:
                grouped.setdefault((run.group, run.plant, run.variant), []).append(json.load(f))
            track_of[run.group] = run.track
    return {key: reduce_cell(summaries, *((None, None) if limit_laps is None else limit_laps[(track_of[key[0]], key[1])]))
            for key, summaries in grouped.items()}


LAP_TIME_LINE = re.compile(r'^lap time\s+([0-9.]+) s', re.MULTILINE)
STANDING_LAP_LINE = re.compile(r'^standing-start lap\s+([0-9.]+) s', re.MULTILINE)


def collocation_limit_laps(mppi_sim, groups, plants, out):
    """(track, plant) -> the limit laps by collocation (docs/LIMIT_LAP.md), flying and from a
    standing start, of the plant row's car on the track, from `mppi-sim --limit-lap
    --limit-lap-method collocation`; NaN where it finds none. Kept in OUT/limit_laps_collocation.json
    and read from there on a rerun (an entry of an older run without the standing start is redone)."""
    cache_path = os.path.join(out, 'limit_laps_collocation.json')
    cache = {}
    if os.path.exists(cache_path):
        with open(cache_path) as f:
            cache = json.load(f)
    limits = {}
    for _, track, _, _ in groups:
        for plant in plants:
            key = f'{track}|{plant}'
            if not isinstance(cache.get(key), list):
                work = os.path.join(out, 'limit_laps', track, plant)
                command = [mppi_sim, '--limit-lap', '--limit-lap-method', 'collocation', '--track', track,
                           *PLANT_ROWS[plant], '--out', work]
                start = time.monotonic()
                done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
                flying = LAP_TIME_LINE.search(done.stdout)
                standing = STANDING_LAP_LINE.search(done.stdout)
                cache[key] = [float(m.group(1)) if done.returncode == 0 and m else float('nan') for m in (flying, standing)]
                print(f'limit lap by collocation, {track} / {plant}: {cache[key][0]:.3f} s, '
                      f'standing start {cache[key][1]:.3f} s '
                      f'({time.monotonic() - start:.0f} s)', flush=True)
                with open(cache_path, 'w') as f:
                    json.dump(cache, f, indent=1)
            limits[(track, plant)] = tuple(cache[key])
    return limits


def faster_than_limit(cell):
    return math.isfinite(cell['fastest_lap_over_limit']) and cell['fastest_lap_over_limit'] < 1.0


def clean(cell):
    return cell['crashes'] == 0 and cell['stalls'] == 0


def best_variant(cells, variants, groups, plants):
    """(variant, its clean mismatch cells, plain's, the mismatch cells there are)."""
    mismatch = [(g, p) for g in groups for p in plants if p in MISMATCH_PLANTS]

    def clean_count(v):
        return sum(1 for g, p in mismatch if (g, p, v) in cells and clean(cells[(g, p, v)]))

    best = max(variants, key=lambda v: (clean_count(v), -list(variants).index(v)))
    plain = clean_count('plain') if 'plain' in variants else None
    return best, clean_count(best), plain, len(mismatch)


# ---- the report -----------------------------------------------------------------------------------
def fmt(value, spec):
    return format(value, spec) if value is not None and math.isfinite(value) else 'n/a'


def plural(n, noun):
    return f'{n} {noun}' + ('' if n == 1 else 's')


def cell_text(cell):
    warning = ' **FASTER THAN THE LIMIT LAP!**' if faster_than_limit(cell) else ''
    unfinished = cell['runs'] - cell['finished_runs']
    laps_done = plural(cell['laps'], 'lap') + (f', {plural(unfinished, "run")} unfinished' if unfinished else '')
    return '<br>'.join([
        f'**{cell["crashes"]} crashes, {cell["stalls"]} stalls** ({laps_done})',
        f'{fmt(cell["mean_speed_mps"], ".2f")} m/s, lap {fmt(cell["mean_lap_over_limit"], ".2f")}x limit',
        f'fastest {fmt(cell["fastest_lap_over_limit"], ".2f")}x{warning}',
        f'slip {fmt(cell["peak_slip_deg"], ".0f")} deg',
        f'du {fmt(cell["mean_abs_steer_step"], ".3f")} / {fmt(cell["mean_abs_throttle_step"], ".3f")}',
        f'opt {fmt(cell["optimizer_ms_p50"], ".1f")} / {fmt(cell["optimizer_ms_p99"], ".1f")} ms',
    ])


def markdown(cells, variants, groups, plants, mode_line, failures):
    lines = ['# Robustness benchmark', '',
             'Generated by `scripts/robustness_benchmark.py` (docs/ROBUSTNESS.md); do not edit by hand.', '',
             mode_line, '',
             'Each cell: crashes and stalls summed over its runs (laps counted); mean speed; mean lap time '
             'over the (flying) limit lap of the plant\'s car (docs/LIMIT_LAP.md); the fastest lap over its limit '
             'lap (lap 1, from rest, over the standing-start one; >= 1 for a physical lap; a lap below is '
             'flagged **FASTER THAN THE LIMIT LAP!**); '
             'peak body slip; mean |d steer| / |d throttle| per control step of the commands sent; '
             'optimizer time per step p50 (mean over runs) / p99 (max over runs).', '']
    best, best_clean, plain_clean, total = best_variant(cells, variants, [g[0] for g in groups], plants)
    if total:
        plain_part = f'; plain: {plain_clean}/{total}' if plain_clean is not None else ''
        lines += [f'**Best variant: {best}**: 0 crashes and 0 stalls in {best_clean}/{total} mismatch cells '
                  f'({", ".join(p for p in plants if p in MISMATCH_PLANTS)}{plain_part}).', '']
    flagged = [k for k, c in cells.items() if faster_than_limit(c)]
    if flagged:
        lines += ['**WARNING: laps faster than the limit lap in ' +
                  ', '.join(' / '.join(k) for k in flagged) + ': the limit lap or the plant is wrong.**', '']
    for group, track, seeds, laps in groups:
        lines += [f'## {group} ({track}, {TARGET_SPEED_MPS:g} m/s target, seeds {", ".join(map(str, seeds))}, '
                  f'{laps} laps each)', '',
                  '| plant | ' + ' | '.join(variants) + ' |',
                  '|---|' + '---|' * len(variants)]
        for plant in plants:
            row = [cell_text(cells[(group, plant, v)]) if (group, plant, v) in cells else 'not run' for v in variants]
            lines.append(f'| {plant} | ' + ' | '.join(row) + ' |')
        lines.append('')
    if failures:
        lines += ['## Failed runs', ''] + [f'- {run.label()}: {error}' for run, error in failures] + ['']
    return '\n'.join(lines)


CSV_FIELDS = ['group', 'plant', 'variant', 'runs', 'laps', 'finished_runs', 'crashes', 'stalls', 'mean_speed_mps',
              'mean_lap_s', 'limit_lap_s', 'mean_lap_over_limit', 'fastest_lap_over_limit', 'peak_slip_deg',
              'mean_abs_steer_step', 'mean_abs_throttle_step', 'optimizer_ms_p50', 'optimizer_ms_p99']


def write_csv(path, cells, variants, groups, plants):
    with open(path, 'w', newline='') as f:
        writer = csv.writer(f)
        writer.writerow(CSV_FIELDS)
        for group, *_ in groups:
            for plant in plants:
                for v in variants:
                    cell = cells.get((group, plant, v))
                    if cell:
                        writer.writerow([group, plant, v] + [
                            f'{cell[k]:.6g}' if isinstance(cell[k], float) else cell[k] for k in CSV_FIELDS[3:]])


def bar_outline(x_centre, width, value, step):
    """A filled bar as one zigzag polyline: vertical strokes `step` apart across its width (the
    figure layer draws lines and markers, no filled shapes)."""
    strokes = max(2, int(width / step) + 1)
    xs, ys = [], []
    for k in range(strokes):
        x = x_centre - width / 2 + width * k / (strokes - 1)
        ends = [0.0, value] if k % 2 == 0 else [value, 0.0]
        xs += [x, x]
        ys += ends
    return xs, ys


def bar_panel(title, y_label, values_by_variant, plants, variants, panel_width_px):
    """A grouped bar chart as a panel of plot/figure_from_json.hpp: bars of the variants side by
    side at each plant, a marker on each bar's top (so that a zero shows) that carries the
    variant's legend entry."""
    series, top = [], 0.0
    slot = 0.8 / len(variants)
    data_per_px = (len(plants) + 0.5) / (0.8 * panel_width_px)
    palette = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f',
               '#bcbd22', '#17becf']
    for i, v in enumerate(variants):
        colour = palette[i % len(palette)]
        xs, ys = [], []
        for j, plant in enumerate(plants):
            value = values_by_variant[v][j]
            if value is None or not math.isfinite(value):
                continue
            x = j + 1 + (i - (len(variants) - 1) / 2) * slot
            xs.append(x)
            ys.append(value)
            top = max(top, value)
            if value > 0:
                bar_x, bar_y = bar_outline(x, 0.85 * slot, value, 1.5 * data_per_px)
                series.append({'x': bar_x, 'y': bar_y, 'colour': colour, 'width_px': 2.0})
        if xs:
            series.append({'x': xs, 'y': ys, 'label': v, 'colour': colour, 'width_px': 0, 'marker': 'square',
                           'marker_px': 5})
    return {'title': title, 'x_label': 'plant: ' + ', '.join(f'{j + 1} {p}' for j, p in enumerate(plants)),
            'y_label': y_label, 'x_axis': {'lo': 0.5, 'hi': len(plants) + 0.5},
            'y_axis': {'lo': 0.0, 'hi': max(1.0, top * 1.15)}, 'legend': 'upper_left', 'series': series}


def figure_json(cells, variants, groups, plants, title):
    panel_width_px = 720
    panels = []
    for group, *_ in groups:
        def values(key):
            out = {}
            for v in variants:
                out[v] = [None if (group, p, v) not in cells else
                          (cells[(group, p, v)]['crashes'] + cells[(group, p, v)]['stalls'] if key == 'incidents'
                           else cells[(group, p, v)][key]) for p in plants]
            return out
        panels.append(bar_panel(f'{group}: crashes + stalls', 'crashes + stalls [-]', values('incidents'), plants,
                                variants, panel_width_px))
        panels.append(bar_panel(f'{group}: mean speed', 'mean speed [m/s]', values('mean_speed_mps'), plants,
                                variants, panel_width_px))
    return {'title': title, 'columns': 2, 'panel_width_px': panel_width_px, 'panel_height_px': 400,
            'panels': panels}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--quick', action='store_true', help='seed 1, 2 laps on the oval only')
    parser.add_argument('--variants', help='comma-separated variant names (default: all in the variants file)')
    parser.add_argument('--plants', help='comma-separated plant rows (default: all): ' + ', '.join(PLANT_ROWS))
    parser.add_argument('--jobs', type=int, default=1, help='mppi-sim processes at a time')
    parser.add_argument('--dask', nargs='?', const='', metavar='ADDRESS',
                        help='run on Dask: a LocalCluster (no ADDRESS) or the scheduler at ADDRESS (tcp://HOST:8786)')
    parser.add_argument('--workers', type=int, default=2, help='with --dask and no ADDRESS: LocalCluster workers')
    parser.add_argument('--out', default='results/robustness', help='run folders and the figure JSON')
    parser.add_argument('--bin', default='build/bin', help='folder of mppi-sim and mppi-plot')
    parser.add_argument('--variants-file', default=VARIANTS_FILE)
    parser.add_argument('--limit-lap-method', choices=['runs', 'collocation'], default='runs',
                        help='the limit lap the laps are measured against: the runs\' own (mppi-sim\'s '
                             'default, QSS) or the car\'s by collocation, solved once per track and plant row')
    parser.add_argument('--report', help='folder of robustness.md / .csv / .png (default: docs/results; '
                                         'with --quick: the --out folder)')
    args = parser.parse_args()
    if args.jobs < 1:
        parser.error('--jobs must be >= 1')

    os.chdir(ROOT)
    all_variants = read_variants(args.variants_file)
    variants = all_variants
    if args.variants:
        names = args.variants.split(',')
        unknown = [n for n in names if n not in all_variants]
        if unknown:
            parser.error(f'unknown variants {unknown} (in {args.variants_file}: {", ".join(all_variants)})')
        variants = {n: all_variants[n] for n in names}
    plants = list(PLANT_ROWS)
    if args.plants:
        plants = args.plants.split(',')
        unknown = [p for p in plants if p not in PLANT_ROWS]
        if unknown:
            parser.error(f'unknown plants {unknown} (valid: {", ".join(PLANT_ROWS)})')
    groups = QUICK_GROUPS if args.quick else FULL_GROUPS
    report_dir = args.report or (args.out if args.quick else 'docs/results')
    mppi_sim = os.path.join(os.path.abspath(args.bin), 'mppi-sim')
    mppi_plot = os.path.join(os.path.abspath(args.bin), 'mppi-plot')
    for binary in (mppi_sim, mppi_plot):
        if not os.access(binary, os.X_OK):
            sys.exit(f'{binary} not found: build it (cmake --build build --target mppi-sim mppi-plot) or pass --bin')

    runs = plan_runs(variants, plants, groups, args.out)
    started = time.monotonic()
    if args.dask is None:
        failures = run_all(runs, mppi_sim, args.jobs)
    else:
        try:
            failures = run_all_on_dask(runs, os.path.abspath(args.bin), args.dask or None, args.workers, args.out)
        except RuntimeError as e:  # mppi_tools' ToolError: a bad address, an unreachable scheduler
            sys.exit(f'robustness_benchmark: {e}')
    limit_laps = None
    if args.limit_lap_method == 'collocation':
        limit_laps = collocation_limit_laps(mppi_sim, groups, plants, args.out)
    cells = reduce_cells(runs, limit_laps)

    mode = 'quick (--quick)' if args.quick else 'full'
    mode_line = (f'Mode: {mode}; {len(runs)} runs; mppi-sim defaults otherwise (K 1920, T 100, CPU backend '
                 f'where there is no GPU); run folders under `{args.out}/runs/`; limit laps by '
                 + ('collocation (`--limit-lap-method collocation`)' if limit_laps is not None else
                    'the runs\' own method (mppi-sim\'s default, QSS)') + '.')
    os.makedirs(report_dir, exist_ok=True)
    os.makedirs(args.out, exist_ok=True)
    md_path = os.path.join(report_dir, 'robustness.md')
    with open(md_path, 'w') as f:
        f.write(markdown(cells, variants, groups, plants, mode_line, failures))
    write_csv(os.path.join(report_dir, 'robustness.csv'), cells, variants, groups, plants)
    fig_path = os.path.join(args.out, 'robustness_figure.json')
    with open(fig_path, 'w') as f:
        json.dump(figure_json(cells, variants, groups, plants,
                              f'MPPI robustness ({mode}, {TARGET_SPEED_MPS:g} m/s target): variants x plants'), f)
    png_path = os.path.join(report_dir, 'robustness.png')
    rc = subprocess.call([mppi_plot, fig_path, png_path])
    print(f'-> {md_path}, {os.path.join(report_dir, "robustness.csv")}, '
          f'{png_path if rc == 0 else "(figure FAILED: mppi-plot exited " + str(rc) + ")"}; '
          f'{format_duration(time.monotonic() - started)}')
    if failures:
        print(f'{len(failures)} runs failed; rerun to retry them', file=sys.stderr)
    return 1 if failures or rc != 0 else 0


if __name__ == '__main__':
    sys.exit(main())
