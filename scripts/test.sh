#!/usr/bin/env bash
# Set up, build, and run the fast suite: every test but the long evidence (the cases tagged
# [slow], ctest label `evidence`: scripts/evidence.sh runs them). Extra arguments go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
mppi_setup
mppi_build -DMPPI_BUILD_TESTS=ON
ctest --test-dir build --output-on-failure -j"$(nproc 2>/dev/null || echo 2)" -LE evidence "$@"
