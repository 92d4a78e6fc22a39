#!/usr/bin/env python3
"""A cost map around a racing line: the track's own AutoRally cost map (.npz), with every cell
the controller may drive on (value below --keep-above) replaced by min(cap, scale * distance to
the line [m]). Cells at or above --keep-above (off the track) keep their value, so the crash
boundary stays where it was. The line: a CSV with x_m, y_m columns, closed (mppi-sim --limit-lap
writes one as DIR/limit_lap.csv).

Usage (Debian's python3 with numpy):
  mppi-sim --limit-lap --track gazebo --out out/ll
  /usr/bin/python3 scripts/racing_line_costmap.py data/autorally/maps/gazebo/gazebo_costmap.npz \\
      out/ll/limit_lap.csv out/ll/racing_line_costmap.npz
  mppi-sim --track gazebo --cost-map out/ll/racing_line_costmap.npz ...
"""
import argparse
import csv
import sys

import numpy as np


def load_line(path):
    with open(path, newline='') as f:
        rows = list(csv.DictReader(f))
    if not rows or 'x_m' not in rows[0] or 'y_m' not in rows[0]:
        sys.exit(f'{path}: need a CSV with columns x_m, y_m')
    return np.array([[float(r['x_m']), float(r['y_m'])] for r in rows])


def distance_to_closed_line(points, line):
    """Distance [m] from each point (N x 2) to the closed polyline `line` (M x 2)."""
    a, b = line, np.roll(line, -1, axis=0)
    best = np.full(len(points), np.inf)
    for i in range(len(a)):
        ab = b[i] - a[i]
        t = np.clip(((points - a[i]) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
        nearest = a[i] + t[:, None] * ab
        best = np.minimum(best, ((points - nearest) ** 2).sum(axis=1))
    return np.sqrt(best)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('costmap', help='the track\'s AutoRally cost map (.npz)')
    ap.add_argument('line', help='the racing line (CSV with x_m, y_m)')
    ap.add_argument('out', help='the cost map to write (.npz)')
    ap.add_argument('--scale', type=float, default=1.0, help='cost per metre from the line (default 1)')
    ap.add_argument('--cap', type=float, default=0.6, help='largest value on the track (default 0.6)')
    ap.add_argument('--keep-above', type=float, default=0.65,
                    help='cells at or above this value are off the track and keep it (default 0.65, '
                         'the AutoRally cost\'s boundary_threshold)')
    args = ap.parse_args()
    try:
        m = dict(np.load(args.costmap))
    except (OSError, ValueError) as e:
        sys.exit(f'{args.costmap}: cannot read the cost map: {e}')
    for key in ('xBounds', 'yBounds', 'pixelsPerMeter', 'channel0'):
        if key not in m:
            sys.exit(f'{args.costmap}: not an AutoRally cost map (no {key})')
    x0, x1 = (float(v) for v in m['xBounds'])
    y0, y1 = (float(v) for v in m['yBounds'])
    ppm = float(m['pixelsPerMeter'][0])
    width, height = int(round((x1 - x0) * ppm)), int(round((y1 - y0) * ppm))
    values = m['channel0'].reshape(height, width)
    xs = x0 + (np.arange(width) + 0.5) / ppm
    ys = y0 + (np.arange(height) + 0.5) / ppm
    gx, gy = np.meshgrid(xs, ys)
    dist = distance_to_closed_line(np.stack([gx.ravel(), gy.ravel()], axis=1), load_line(args.line))
    on_line = np.minimum(args.cap, args.scale * dist.reshape(height, width))
    m['channel0'] = np.where(values >= args.keep_above, values, on_line).astype(np.float32).ravel()
    np.savez(args.out, **m)
    print(f'{args.out}: cost map around {args.line} ({width} x {height} cells)')


if __name__ == '__main__':
    main()
