#!/usr/bin/env bash
# Re-runs the plant comparison of docs/CALIBRATION.md ("The network as the plant" and "What the
# network can and cannot hold"): MPPI on the AutoRally network driving the network itself (the
# real car as the network learned it, and a perfect model for the controller), then the
# single-track calibrations with and without those closed-loop logs, each judged on the
# held-out scripted manoeuvres and on held-out closed-loop logs (other seed, other tracks).
#
#   scripts/calibration_plants.sh            # about 10 min on 2 cores -> out/calibration_plants/
#
# Needs build/bin/mppi-sim and build/bin/mppi-fit (scripts/demo.sh or cmake --build build).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin
out=out/calibration_plants
mkdir -p "$out"

# 1. The network as the plant: Gazebo oval 10 laps (seeds 1-3), Marietta and CCRF 3 laps.
net_run() {  # NAME TRACK SEED LAPS
  echo "[calibration_plants] network on the network: $2 seed $3, $4 laps"
  "$bin/mppi-sim" --track "$2" --speed 8 --laps "$4" --seed "$3" --threads 1 --plant autorally-nn \
    --quiet --out "$out/$1" > /dev/null
}
net_run network_gazebo_s1 gazebo 1 10 &
net_run network_gazebo_s2 gazebo 2 10 &
wait
net_run network_gazebo_s3 gazebo 3 10 &
net_run network_marietta_s1 marietta 1 3 &
wait
net_run network_ccrf_s1 ccrf 1 3

# 2. Calibrations: every fit is judged on the held-out closed-loop logs as well.
base=max_steer_rad,stall_torque_Nm,no_load_speed_mps,brake_torque_ratio,rolling_resistance,aero_drag_kgpm,tyre.B,tyre.C,tyre.D,tyre.E,tyre.Sv
axles=rear_tyre_B_scale,rear_tyre_C_scale,rear_tyre_D_scale
heldout=(--heldout-log "$out/network_gazebo_s2/log.csv" --heldout-log "$out/network_marietta_s1/log.csv"
         --heldout-log "$out/network_ccrf_s1/log.csv")
train_log=(--train-log "$out/network_gazebo_s1/log.csv")
fit() {  # NAME ARGS...
  local name=$1
  shift
  echo "[calibration_plants] mppi-fit calibrate $name"
  "$bin/mppi-fit" calibrate "$@" "${heldout[@]}" --out "$out/$name" > "$out/$name.log"
}
fit single_track --estimate "$base" &
fit actuated --estimate "$base,$axles,steer_lag_s,throttle_lag_s,steer_cubic,steer_offset" &
wait
fit stateless --estimate "$base,$axles,steer_cubic,steer_offset" &
fit effective_inertia --estimate "$base,$axles,steer_cubic,steer_offset,yaw_inertia_kgm2" &
wait
fit single_track_closed_loop --estimate "$base" "${train_log[@]}" &
fit actuated_closed_loop --estimate "$base,$axles,steer_lag_s,throttle_lag_s,steer_cubic,steer_offset" "${train_log[@]}" &
wait
fit stateless_closed_loop --estimate "$base,$axles,steer_cubic,steer_offset" "${train_log[@]}" &
fit effective_inertia_closed_loop --estimate "$base,$axles,steer_cubic,steer_offset,yaw_inertia_kgm2" "${train_log[@]}" &
wait

for d in single_track actuated stateless effective_inertia single_track_closed_loop actuated_closed_loop \
         stateless_closed_loop effective_inertia_closed_loop; do
  echo "== $d"
  grep -E "held-out" "$out/$d/summary.txt"
done
