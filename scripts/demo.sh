#!/usr/bin/env bash
# Set up, build, and drive 5 laps of the Gazebo oval with MPPI on the real AutoRally network at
# AutoRally's operating point: the upstream controller settings (path_integral_nn.launch: 1920
# samples, 100 steps at 50 Hz, its noise stds and max throttle 0.65, its 5-point plan smoothing;
# mppi-sim's defaults) and 8 m/s desired speed, on the single-track Pacejka plant calibrated to
# the network (docs/CALIBRATION.md). Results in out/demo/ (track_slip.png colours the trail by body slip).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
mppi_setup
mppi_build -DMPPI_BUILD_TESTS=OFF
./build/bin/mppi-sim --track gazebo --model autorally-nn --speed 8 --laps 5 --out out/demo "$@"
