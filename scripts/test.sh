#!/usr/bin/env bash
# Set up, build, and run every test (ctest). Extra arguments go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
mppi_setup
mppi_build -DMPPI_BUILD_TESTS=ON
ctest --test-dir build --output-on-failure -j"$(nproc 2>/dev/null || echo 2)" "$@"
