#!/usr/bin/env bash
# The fast suite under sanitizers (-O1), each in a build folder of its own:
#   build-asan  AddressSanitizer + UndefinedBehaviorSanitizer (+ LeakSanitizer), clang: the test
#               programs mppi-tests (every case but those tagged [slow]) and mppi-ocs-tests
#   build-tsan  ThreadSanitizer, GCC: mppi-thread-tests, the threaded parts (tests/CMakeLists.txt)
# Any report stops the program with a non-zero exit (-fno-sanitize-recover=all, halt_on_error),
# so the run fails. Only the test programs and the libraries they link are built (no
# benchmarks, no command-line programs, no Python module).
#
# Usage: scripts/sanitize.sh [asan|tsan|all]   (default all)
#
# Choices, and what is left out:
# - ASan is built by clang with one version of each hot kernel (MPPI_NO_MULTIVERSION): the
#   AVX-512 / AVX2 / baseline clones are the same source compiled three times, and clang
#   compiles the template-heavy rollouts in about half GCC's time; together they halve the
#   build. -ffp-contract=off: clang would fuse a * b + c where GCC's baseline build does not
#   (even when folding constants), and the fast-math tests check exact saturation values.
#   The [slow] cases (scripts/evidence.sh) are left out: their code runs under ASan in their
#   fast siblings. So are the fast suite's cases tagged [no-asan]: whole diagnoses with every
#   candidate effect, seconds in the Release build and a quarter of an hour under ASan, whose
#   rules run under ASan in the unit cases beside them. LeakSanitizer leaves out what tests/lsan.supp names (fontconfig, the
#   Vulkan drivers and their LLVM). The Python tests and the programs' command-line tests run
#   only in the normal build.
# - TSan: the OpenMP schedules (ThreadSchedule::kDynamic / kStatic). Debian's libgomp is not
#   built with -fsanitize=thread, so TSan does not see its barriers and reports races that are
#   not there; the default schedule, oneTBB work stealing, is what runs under TSan. Python
#   threads releasing the GIL are not run under TSan either: CPython is not instrumented.
set -euo pipefail
cd "$(dirname "$0")/.."
which="${1:-all}"
jobs=$(nproc 2>/dev/null || echo 2)
source scripts/setup.sh
MPPI_DEBIAN_PACKAGES+=(clang libclang-rt-14-dev libomp-dev)
mppi_setup

sanitizer_build() {  # <dir> <compiler: gcc|clang> <flags> <targets...> [-- <cmake options...>]
  local dir=$1 compiler=$2 flags=$3
  shift 3
  local targets=() options=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do targets+=("$1"); shift; done
  [ $# -gt 0 ] && shift && options=("$@")
  local cc=gcc cxx=g++
  [ "$compiler" = clang ] && cc=clang cxx=clang++
  local t0=$SECONDS
  CC=$cc CXX=$cxx cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Sanitize \
    -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -g1 -fno-omit-frame-pointer $flags" \
    -DCMAKE_EXE_LINKER_FLAGS_SANITIZE="$flags" -DCMAKE_SHARED_LINKER_FLAGS_SANITIZE="$flags" \
    -DMPPI_BUILD_TESTS=ON -DMPPI_BUILD_BENCH=OFF -DMPPI_BUILD_APPS=OFF "${options[@]}" >/dev/null
  cmake --build "$dir" -j"$jobs" --target "${targets[@]}"
  echo "[sanitize] $dir: ${targets[*]} built in $((SECONDS - t0)) s"
}

# Runs mppi-tests in two processes (one per core), split by tags into halves of about equal
# time; neither runs the test cases tagged [slow] or [no-asan].
run_asan() {
  export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:detect_stack_use_after_return=0:strict_string_checks=1"
  export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0"
  export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
  local t0=$SECONDS bin=build-asan/bin/mppi-tests
  "$bin" "~[slow]~[no-asan][sysid],~[slow]~[no-asan][diagnose],~[slow]~[no-asan][vulkan]" >build-asan/part1.log 2>&1 &
  local pid1=$!
  local rc2=0 rc1=0
  { "$bin" "~[slow]~[no-asan]~[sysid]~[diagnose]~[vulkan]" && build-asan/bin/mppi-ocs-tests; } >build-asan/part2.log 2>&1 || rc2=$?
  wait "$pid1" || rc1=$?
  tail -n 3 build-asan/part1.log build-asan/part2.log
  echo "[sanitize] ASan+UBSan suite ran in $((SECONDS - t0)) s"
  if [ "$rc1" -ne 0 ] || [ "$rc2" -ne 0 ]; then
    grep -h -B2 -A30 "ERROR: AddressSanitizer\|runtime error\|ERROR: LeakSanitizer\|FAILED" \
      build-asan/part1.log build-asan/part2.log | head -n 200
    echo "[sanitize] ASan+UBSan: FAILED" >&2
    return 1
  fi
}

run_tsan() {
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp"
  local t0=$SECONDS
  build-tsan/bin/mppi-thread-tests
  echo "[sanitize] TSan threaded tests ran in $((SECONDS - t0)) s"
}

case "$which" in
  asan|all)
    sanitizer_build build-asan clang "-fsanitize=address,undefined -fno-sanitize-recover=all -DMPPI_NO_MULTIVERSION -ffp-contract=off -Wno-pass-failed" \
      mppi-tests mppi-ocs-tests
    run_asan ;;&
  tsan|all)
    # MPPI_NO_MULTIVERSION: the ifunc resolvers of the target_clones kernels run while the
    # program is relocated, before the TSan runtime is up; instrumented, they crash at start.
    sanitizer_build build-tsan gcc "-fsanitize=thread -DMPPI_NO_MULTIVERSION" mppi-thread-tests -- -DMPPI_VULKAN=OFF
    run_tsan ;;
  asan) ;;
  *) echo "usage: $0 [asan|tsan|all]" >&2; exit 2 ;;
esac
