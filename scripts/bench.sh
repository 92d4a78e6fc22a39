#!/usr/bin/env bash
# Builds and runs mppi-bench (Google Benchmark) with JSON output into build/bench/, then prints
# a table of the medians and the ratio full MPPI iteration / bare network limit.
#   scripts/bench.sh                      # everything, 10 repetitions
#   scripts/bench.sh --benchmark_filter=BM_MppiIteration   # extra args go to mppi-bench
# Environment: BUILD_DIR (default build), REPS (default 10), MIN_TIME (default 0.5 s per rep),
# NO_BUILD=1 (use the existing binary). Timings on a shared machine are noisy: read medians.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
REPS=${REPS:-10}
MIN_TIME=${MIN_TIME:-0.5}

if [ "${NO_BUILD:-0}" != 1 ] || [ ! -x "$BUILD_DIR/bin/mppi-bench" ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD_DIR" -j"$(nproc 2>/dev/null || echo 2)" --target mppi-bench
fi

mkdir -p "$BUILD_DIR/bench"
stamp=$(date +%Y%m%d-%H%M%S)
out="$BUILD_DIR/bench/mppi-bench-$stamp.json"
"$BUILD_DIR/bin/mppi-bench" \
  --benchmark_repetitions="$REPS" \
  --benchmark_min_time="$MIN_TIME" \
  --benchmark_out="$out" --benchmark_out_format=json \
  --benchmark_format=console "$@"
cp "$out" "$BUILD_DIR/bench/latest.json"
echo
echo "JSON: $out (and $BUILD_DIR/bench/latest.json)"
python3 - "$out" <<'PY'
import json, re, sys
doc = json.load(open(sys.argv[1]))
ctx = doc.get("context", {})
print(f"host {ctx.get('host_name', '?')}, {ctx.get('num_cpus', '?')} CPUs @ "
      f"{ctx.get('mhz_per_cpu', '?')} MHz, {ctx.get('cpu_model', '')}, dispatch: "
      f"{ctx.get('dispatch_isa', '?')}")
rows = {}
for b in doc["benchmarks"]:
    if b.get("run_type") == "aggregate" and b.get("aggregate_name") not in ("median", "cv"):
        continue
    name = re.sub(r"/(real|process)_time$", "", b.get("run_name", b["name"]))
    r = rows.setdefault(name, {"ms": [], "cpu": [], "items": None, "cv": None})
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b.get("time_unit", "ns")]
    if b.get("run_type") == "aggregate" and b["aggregate_name"] == "median":
        r["median"] = b["real_time"] * scale
        r["cpu_median"] = b["cpu_time"] * scale
        r["items"] = b.get("items_per_second")
    elif b.get("run_type") == "aggregate" and b["aggregate_name"] == "cv":
        r["cv"] = b["real_time"]
    else:
        r["ms"].append(b["real_time"] * scale)
        r["cpu"].append(b["cpu_time"] * scale)
        r["items"] = r["items"] or b.get("items_per_second")
def median(v):
    v = sorted(v); n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])
# wall = what a control step takes; cpu = the main thread's CPU time (with 1 thread a check on
# the wall time when the machine is shared: wall >> cpu means the run was preempted)
print(f"\n{'benchmark':<30} {'wall ms':>9} {'cv':>6} {'cpu ms':>9} {'Msteps/s':>9}")
med = {}
for name, r in rows.items():
    m = r.get("median", median(r["ms"]) if r["ms"] else float("nan"))
    c = r.get("cpu_median", median(r["cpu"]) if r["cpu"] else float("nan"))
    med[name] = m
    cv = f"{100 * r['cv']:.1f}%" if r["cv"] is not None else "-"
    items = f"{r['items'] / 1e6:.1f}" if r["items"] else "-"
    print(f"{name:<30} {m:>9.3f} {cv:>6} {c:>9.3f} {items:>9}")
print()
for name, m in med.items():
    mm = re.match(r"BM_MppiIteration/(threads:\d+)", name)
    if mm and f"BM_BareLimit/{mm.group(1)}" in med:
        bare = med[f"BM_BareLimit/{mm.group(1)}"]
        print(f"full/bare ({mm.group(1)}): {m:.3f} / {bare:.3f} ms = {m / bare:.2f}x (target <= 1.5x)")
        th = mm.group(1)
        parts = [f"BM_NoiseSampling/{th}", f"BM_Rollout/{th}"]
        if all(p in med for p in parts):
            s, r = med[parts[0]], med[parts[1]]
            print(f"  of which sampling {s:.3f} ms ({100 * s / m:.0f}%), rollout {r:.3f} ms "
                  f"({100 * r / m:.0f}%, network alone {med.get(f'BM_NetworkRollout/{th}', float('nan')):.3f}),"
                  f" weights/update/rest {m - s - r:.3f} ms")
PY
