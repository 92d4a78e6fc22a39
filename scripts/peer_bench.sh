#!/usr/bin/env bash
# Runs the peer benchmark (MPPI-Generic cross-implementation workload) and the scaling runs of
# mppi-bench with JSON output into build/bench/, then prints our figures beside the published
# ones (scripts/peer_compare.py).
#   scripts/peer_bench.sh                                  # BM_Peer* and BM_AutoRallyScaling
#   scripts/peer_bench.sh --benchmark_filter=BM_PeerIteration   # extra args go to mppi-bench
# Environment: BUILD_DIR (default build), MIN_TIME (default 1 s per benchmark), NO_BUILD=1.
# On a shared machine read the medians and p99: other processes' load shows up in means / max.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
MIN_TIME=${MIN_TIME:-1}
if [ "${NO_BUILD:-0}" != 1 ] || [ ! -x "$BUILD_DIR/bin/mppi-bench" ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD_DIR" -j"$(nproc 2>/dev/null || echo 2)" --target mppi-bench
fi
mkdir -p "$BUILD_DIR/bench"
out="$BUILD_DIR/bench/peer-$(date +%Y%m%d-%H%M%S).json"
"$BUILD_DIR/bin/mppi-bench" --benchmark_filter='BM_Peer|BM_AutoRallyScaling' \
  --benchmark_min_time="$MIN_TIME" --benchmark_out="$out" --benchmark_out_format=json "$@"
echo "JSON: $out"
python3 scripts/peer_compare.py "$out"
