#!/usr/bin/env bash
# Set up, build, and drive 5 laps of the Gazebo oval with MPPI on the real AutoRally network
# (the single-track Pacejka car is the simulated plant). Results in out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
mppi_setup
mppi_build -DMPPI_BUILD_TESTS=OFF
./build/bin/mppi-sim --track gazebo --model autorally-nn --speed 6 --laps 5 --out out/demo "$@"
