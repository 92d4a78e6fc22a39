#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, clang, ASan + UBSan) in build-fuzz/ and runs each one
# for at most [seconds] (default 20) or [runs] executions (default: no limit), one after the
# other. Seeds: fuzz/corpus/<target>/ (never written); the growing corpus: build-fuzz/corpus/.
# A crash, leak, sanitizer report, timeout or an exception other than mppi::Error fails the run;
# the input is kept as build-fuzz/artifacts/<target>-crash-... (reproduce: the target binary
# with that file as its argument). Figures per target: build-fuzz/fuzz-summary.txt.
# OpenCV's image decoders refuse images above 1 Mpixel in these runs (OPENCV_IO_MAX_IMAGE_PIXELS;
# its default is 1 Gpixel): a few bytes of WebP or PNG header can ask for a 1 GB image, which
# OpenCV allocates and fills before the cost-map loader compares its size with the map's, and
# a fuzzer that finds such a header would spend its time decoding it (fuzz_cost_map_image's
# map has 256 pixels).
#
# Usage: scripts/fuzz.sh [seconds] [runs] [target ...]   e.g. scripts/fuzz.sh 600 1000000 fuzz_npz
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-20}"
runs="${2:--1}"
shift $(($# > 2 ? 2 : $#))

source scripts/setup.sh
MPPI_DEBIAN_PACKAGES+=(clang libclang-rt-14-dev libomp-dev)
mppi_setup

jobs=$(nproc 2>/dev/null || echo 2)
t0=$SECONDS
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Fuzz \
  -DCMAKE_CXX_FLAGS_FUZZ="-O1 -g -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all" \
  -DCMAKE_EXE_LINKER_FLAGS_FUZZ="-fsanitize=address,undefined" -DMPPI_BUILD_FUZZERS=ON -DMPPI_BUILD_TESTS=OFF \
  -DMPPI_BUILD_BENCH=OFF -DMPPI_BUILD_APPS=OFF -DMPPI_VULKAN=OFF >/dev/null
cmake --build build-fuzz -j"$jobs" --target mppi-fuzzers
echo "[fuzz] built in $((SECONDS - t0)) s"

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for d in fuzz/corpus/*/; do targets+=("$(basename "$d")"); done
fi
mkdir -p build-fuzz/artifacts
summary=build-fuzz/fuzz-summary.txt
printf '%-28s %12s %8s %8s %8s %s\n' target executions exec/s corpus seconds result >"$summary"
failed=0
for t in "${targets[@]}"; do
  mkdir -p "build-fuzz/corpus/$t"
  log="build-fuzz/$t.log"
  start=$SECONDS
  rc=0
  ASAN_OPTIONS="detect_leaks=1" UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1" OPENCV_IO_MAX_IMAGE_PIXELS=1048576 \
    "build-fuzz/fuzz/$t" -max_total_time="$seconds" -runs="$runs" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="build-fuzz/artifacts/$t-" \
    "build-fuzz/corpus/$t" "fuzz/corpus/$t" >"$log" 2>&1 || rc=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
  speed=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
  corpus=$(find "build-fuzz/corpus/$t" "fuzz/corpus/$t" -type f | wc -l)
  result=ok
  if [ "$rc" -ne 0 ]; then
    result="FAILED (rc $rc, see $log)"
    failed=1
    grep -A25 "ERROR:\|runtime error\|deadly signal\|uncaught\|terminate called" "$log" | head -n 40 || true
  fi
  printf '%-28s %12s %8s %8s %8s %s\n' "$t" "$execs" "$speed" "$corpus" $((SECONDS - start)) "$result" | tee -a "$summary"
done
cat "$summary"
exit "$failed"
