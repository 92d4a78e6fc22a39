#!/usr/bin/env bash
# The test suite under sanitizers, each in its own build folder (GCC, -O1):
#   build-asan: AddressSanitizer + UndefinedBehaviorSanitizer (and LeakSanitizer) over the suite;
#   build-tsan: ThreadSanitizer over the threaded parts.
# Any sanitizer report stops the program with a non-zero exit (-fno-sanitize-recover=all,
# halt_on_error=1), so the run fails. Usage: scripts/sanitize.sh [asan|tsan|all]
set -euo pipefail
cd "$(dirname "$0")/.."
which="${1:-all}"
jobs=$(nproc 2>/dev/null || echo 2)

# Only the test program and the libraries it links: no benchmarks, no command-line programs,
# no Python module.
sanitizer_build() {  # <dir> <flags>
  local dir=$1 flags=$2
  local t0=$SECONDS
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Sanitize \
    -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -g1 -fno-omit-frame-pointer $flags" \
    -DCMAKE_EXE_LINKER_FLAGS_SANITIZE="$flags" -DCMAKE_SHARED_LINKER_FLAGS_SANITIZE="$flags" \
    -DMPPI_BUILD_TESTS=ON -DMPPI_BUILD_BENCH=OFF -DMPPI_BUILD_APPS=OFF >/dev/null
  cmake --build "$dir" -j"$jobs" --target mppi-tests
  echo "[sanitize] $dir built in $((SECONDS - t0)) s"
}
