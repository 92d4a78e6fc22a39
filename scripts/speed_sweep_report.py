#!/usr/bin/env python3
"""Table (Markdown, stdout) and plot (SVG) of a target-speed sweep: reads OUT/<track>_<speed>/
summary.json as written by mppi-sim (scripts/speed_sweep.sh) and writes OUT/speed_sweep.svg.
Standard library only."""
import json
import math
import statistics
import sys
from pathlib import Path

TRACK_COLOURS = {"gazebo": "#1f77b4", "marietta": "#d62728", "ccrf": "#2ca02c"}


def load_runs(out):
    runs = []
    for summary in sorted(Path(out).glob("*_*/summary.json")):
        track, speed = summary.parent.name.rsplit("_", 1)
        s = json.loads(summary.read_text())
        laps = [t for t in s.get("lap_times_s") or [] if t is not None]
        runs.append({
            "track": track, "target": float(speed), "laps": s["laps_completed"], "crashes": s["crashes"],
            "stalls": s.get("stalls", 0), "incidents": s["crashes"] + s.get("stalls", 0),
            "mean": s["mean_speed_mps"], "best": min(laps) if laps else math.nan,
            "median": statistics.median(laps) if laps else math.nan,
            "slip_deg": math.degrees(s.get("peak_slip_angle_rad") or 0.0),
            "slip95_deg": math.degrees(s.get("p95_slip_angle_rad") or 0.0),
            "lat": s.get("peak_lateral_accel_mps2") or 0.0, "time": s["sim_time_s"],
        })
    runs.sort(key=lambda r: (list(TRACK_COLOURS).index(r["track"]) if r["track"] in TRACK_COLOURS else 9, r["target"]))
    return runs


def table(runs):
    rows = ["| track | target [m/s] | laps | crashes | mean speed [m/s] | best lap [s] | median lap [s] | "
            "peak body slip [deg] | p95 body slip [deg] | peak lateral accel [m/s^2] |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        crashes = f"{r['crashes']}" + (f" + {r['stalls']} stalled" if r["stalls"] else "")
        rows.append(f"| {r['track']} | {r['target']:g} | {r['laps']} | {crashes} | {r['mean']:.2f} | "
                    f"{r['best']:.2f} | {r['median']:.2f} | {r['slip_deg']:.1f} | {r['slip95_deg']:.1f} | {r['lat']:.1f} |")
    return "\n".join(rows)


def svg(runs, path):
    """Three panels over target speed: mean speed, crashes (stalls included), peak body slip; one line per track."""
    panels = [("mean speed [m/s]", "mean"), ("crashes + stalls", "incidents"), ("peak body slip [deg]", "slip_deg")]
    w, h, pad = 300, 240, 50
    targets = sorted({r["target"] for r in runs}) or [0.0, 1.0]
    x0, x1 = min(targets), max(targets)
    x1 = x1 if x1 > x0 else x0 + 1
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{len(panels) * (w + pad) + pad}" height="{h + 2 * pad}" '
             'font-family="sans-serif" font-size="12">', '<rect width="100%" height="100%" fill="white"/>']
    for i, (label, key) in enumerate(panels):
        ox = pad + i * (w + pad)
        vals = [r[key] for r in runs if not math.isnan(r[key])] or [0.0]
        if key == "mean":
            vals += targets  # the reference line (mean = target) stays inside the panel
        y0, y1 = min(0.0, min(vals)), max(vals) * 1.1 or 1.0
        sx = lambda x: ox + (x - x0) / (x1 - x0) * w
        sy = lambda y: pad + h - (y - y0) / (y1 - y0) * h
        parts.append(f'<rect x="{ox}" y="{pad}" width="{w}" height="{h}" fill="none" stroke="black"/>')
        parts.append(f'<text x="{ox + w / 2}" y="{pad - 10}" text-anchor="middle">{label}</text>')
        parts.append(f'<text x="{ox + w / 2}" y="{pad + h + 35}" text-anchor="middle">target speed [m/s]</text>')
        for t in targets:
            parts.append(f'<text x="{sx(t):.1f}" y="{pad + h + 15}" text-anchor="middle">{t:g}</text>')
        for frac in (0.0, 0.5, 1.0):
            y = y0 + frac * (y1 - y0)
            parts.append(f'<text x="{ox - 5}" y="{sy(y) + 4:.1f}" text-anchor="end">{y:.3g}</text>')
        if key == "mean":  # the target itself, for reference
            parts.append(f'<line x1="{sx(x0):.1f}" y1="{sy(x0):.1f}" x2="{sx(x1):.1f}" y2="{sy(x1):.1f}" '
                         'stroke="grey" stroke-dasharray="4,3"/>')
        for track, colour in TRACK_COLOURS.items():
            pts = [(r["target"], r[key]) for r in runs if r["track"] == track and not math.isnan(r[key])]
            if not pts:
                continue
            line = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in pts)
            parts.append(f'<polyline points="{line}" fill="none" stroke="{colour}" stroke-width="2"/>')
            for x, y in pts:
                parts.append(f'<circle cx="{sx(x):.1f}" cy="{sy(y):.1f}" r="3" fill="{colour}"/>')
    for j, (track, colour) in enumerate(TRACK_COLOURS.items()):
        parts.append(f'<text x="{pad + 10 + 90 * j}" y="{h + 2 * pad - 2}" fill="{colour}">{track}</text>')
    parts.append("</svg>")
    Path(path).write_text("\n".join(parts) + "\n")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "out/speed_sweep"
    runs = load_runs(out)
    if not runs:
        sys.exit(f"no {out}/<track>_<speed>/summary.json found")
    svg(runs, Path(out) / "speed_sweep.svg")
    print(table(runs))


if __name__ == "__main__":
    main()
