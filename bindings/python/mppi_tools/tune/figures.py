"""The study's figures as figure JSON (plot/figure_from_json.hpp) drawn to PNG by mppi-plot: the
optimisation history and the parameter importances."""
import json
import math
import subprocess

from .. import paths
from ..errors import ToolError

BLUE, RED, GREEN, GREY = '#1f77b4', '#d62728', '#2ca02c', '#7f7f7f'


def history_panel(records, infeasible_at):
    """records: [(number, value, feasible)]; infeasible trials drawn at `infeasible_at` (crosses)."""
    ok = [(n, v) for n, v, f in records if f]
    bad = [n for n, v, f in records if not f]
    best, line = math.inf, ([], [])
    for n, v, f in sorted(records):
        if f and v < best:
            best = v
        if math.isfinite(best):
            line[0].append(n)
            line[1].append(best)
    series = []
    if ok:
        series.append({'x': [n for n, _ in ok], 'y': [v for _, v in ok], 'label': 'trial (0 crashes)',
                       'colour': BLUE, 'width_px': 0, 'marker': 'circle', 'marker_px': 6})
    if bad:
        series.append({'x': bad, 'y': [infeasible_at] * len(bad), 'label': 'crash / stall (infeasible)',
                       'colour': RED, 'width_px': 0, 'marker': 'cross', 'marker_px': 7})
    if line[0]:
        series.append({'x': line[0], 'y': line[1], 'label': 'best so far', 'colour': GREEN, 'width_px': 2.0})
    values = [v for _, v in ok] + ([infeasible_at] if bad else [])
    lo = min(values) if values else 1.0
    hi = max(values) if values else 2.0
    pad = max(0.02, 0.08 * (hi - lo))
    numbers = [n for n, _, _ in records] or [0]
    return {'title': 'optimisation history', 'x_label': 'trial', 'y_label': 'mean lap / limit lap [-]',
            'x_axis': {'lo': min(numbers) - 0.5, 'hi': max(numbers) + 0.5}, 'y_axis': {'lo': lo - pad, 'hi': hi + pad},
            'legend': 'upper_right', 'series': series}


def importance_panel(importance):
    """Vertical bars (zigzag strokes: the figure layer draws lines, not filled shapes)."""
    names = list(importance)
    series = []
    for i, name in enumerate(names, 1):
        value = importance[name]
        xs, ys = [], []
        for k in range(17):
            x = i - 0.3 + 0.6 * k / 16
            xs += [x, x]
            ys += [0.0, value] if k % 2 == 0 else [value, 0.0]
        series.append({'x': xs, 'y': ys, 'colour': BLUE, 'width_px': 2.0})
    series.append({'x': list(range(1, len(names) + 1)), 'y': [importance[n] for n in names],
                   'label': 'variance share explained', 'colour': BLUE, 'width_px': 0, 'marker': 'square',
                   'marker_px': 5})
    return {'title': 'parameter importances', 'x_label': ', '.join(f'{i} {n}' for i, n in enumerate(names, 1)),
            'y_label': 'eta^2 [-]', 'x_axis': {'lo': 0.5, 'hi': len(names) + 0.5},
            'y_axis': {'lo': 0.0, 'hi': max([1e-3] + list(importance.values())) * 1.15}, 'legend': 'upper_right',
            'series': series}


def draw(figure, json_path, png_path, bin_dir=None):
    """Writes the figure JSON and has mppi-plot draw it; ToolError naming the file on failure."""
    with open(json_path, 'w') as f:
        json.dump(figure, f)
    done = subprocess.run([paths.program('mppi-plot', bin_dir), json_path, png_path], capture_output=True, text=True)
    if done.returncode != 0:
        raise ToolError(f'mppi-plot {json_path}: {done.stderr.strip() or done.stdout.strip()}')
    return png_path


def single(panel, title, width_px=900):
    return {'title': title, 'columns': 1, 'panel_width_px': width_px, 'panel_height_px': 420, 'panels': [panel]}
