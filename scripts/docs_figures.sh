#!/usr/bin/env bash
# Regenerates every figure shipped in docs/ (and shown by the README) with the commands that
# produced them (see the text around each image in docs/), writing the runs to out/docs_figures/
# and copying only the PNGs into docs/. Closed-loop runs are
# checked against the lap times recorded in docs/results/*.json: plotting must not change them.
#
#   scripts/docs_figures.sh           # all but the Vulkan run (about 10 min on 2 loaded cores)
#   scripts/docs_figures.sh --vulkan  # also the 5 Vulkan laps (lavapipe: ~280 ms a step, ~15 min more)
#   scripts/docs_figures.sh --diagnose-docs  # also rewrite results/diagnose/dart (report and figures)
#
# Needs build/bin/mppi-sim and build/bin/mppi-fit (scripts/demo.sh or cmake --build build).
set -euo pipefail
cd "$(dirname "$0")/.."
vulkan=0
diagnose_docs=0
for arg in "$@"; do
  case "$arg" in
    --vulkan) vulkan=1 ;;
    --diagnose-docs) diagnose_docs=1 ;;
    *) echo "usage: $0 [--vulkan] [--diagnose-docs]" >&2; exit 2 ;;
  esac
done
bin=build/bin
out=out/docs_figures
mkdir -p "$out"
py=/usr/bin/python3
[ -x "$py" ] || py=python3

# mppi-sim run NAME ARGS...: drive, copy track.png to docs/results/NAME.png, compare the laps.
sim() {
  local name=$1
  shift
  echo "[docs_figures] mppi-sim $* -> docs/results/$name.png"
  "$bin/mppi-sim" "$@" --quiet --out "$out/$name" > /dev/null
  cp "$out/$name/track.png" "docs/results/$name.png"
  if [ -f "docs/results/$name.json" ]; then
    "$py" - "$out/$name/summary.json" "docs/results/$name.json" <<'PY'
import json, sys
new, old = (json.load(open(p)) for p in sys.argv[1:3])
same = all(new[k] == old[k] for k in ("laps_completed", "crashes", "lap_times_s"))
print("  laps", [round(t, 2) for t in new["lap_times_s"]], "crashes", new["crashes"],
      "- same as recorded" if same else "- DIFFERENT from " + sys.argv[2])
sys.exit(0)  # a difference is reported, not fatal: the runs are the current code's
PY
  fi
}

# Closed loop on the Gazebo oval (README, docs/PHYSICS.md, docs/VULKAN.md) and CCRF.
sim gazebo_nn_6mps_5laps --laps 5 --seed 1 --backend cpu
sim gazebo_double_track_6mps_3laps --model double-track --plant double-track --laps 3 --backend cpu
sim gazebo_full_vehicle_6mps_3laps --model full-vehicle --plant full-vehicle --laps 3 --backend cpu
sim gazebo_single_track_on_full_vehicle_6mps_3laps --model single-track --plant full-vehicle --laps 3 --backend cpu
sim ccrf_nn_6mps --track ccrf --laps 1 --backend cpu
# The limit lap of the default plant (docs/LIMIT_LAP.md).
for track in gazebo ccrf; do
  echo "[docs_figures] mppi-sim --limit-lap --track $track -> docs/results/limit_lap_$track.png"
  "$bin/mppi-sim" --limit-lap --track "$track" --out "$out/limit_lap_$track" > /dev/null
  cp "$out/limit_lap_$track/limit_lap.png" "docs/results/limit_lap_$track.png"
done
if [ "$vulkan" = 1 ]; then
  sim gazebo_nn_6mps_5laps_vulkan_lavapipe --laps 5 --seed 1 --backend vulkan
fi

# The estimation protocol and the estimates (docs/ESTIMATION.md, docs/PHYSICS.md).
truth=docs/results/estimation/protocol_truth_full_vehicle.yaml
est=docs/results/estimation
echo "[docs_figures] mppi-fit protocol (interleaved, sequential)"
"$bin/mppi-fit" protocol --params "$truth" --out "$out/protocol" > /dev/null
"$bin/mppi-fit" protocol --params "$truth" --layout sequential --out "$out/protocol_seq" > /dev/null
cp "$out/protocol/protocol.png" docs/results/protocol.png
estimate() {  # NAME ARGS...: mppi-fit estimate ARGS --out out/NAME, copy its PNGs to docs/results/estimation/NAME
  local name=$1
  shift
  echo "[docs_figures] mppi-fit estimate -> $est/$name"
  "$bin/mppi-fit" estimate "$@" --out "$out/$name" > /dev/null
  for png in convergence.png validation.png; do
    if [ -f "$est/$name/$png" ]; then cp "$out/$name/$png" "$est/$name/$png"; fi
  done
}
estimate protocol_alm "$out/protocol/train.csv" --model full-vehicle --truth "$truth" \
  --validate-recording "$out/protocol/validation.csv" --process-scale 0.1 --walk-std 0.001
estimate protocol_ukf "$out/protocol/train.csv" --model full-vehicle --truth "$truth" \
  --validate-recording "$out/protocol/validation.csv" --process-scale 0.1 --walk-std 0.001 --estimator ukf
estimate protocol_alm_sequential "$out/protocol_seq/train.csv" --model full-vehicle --truth "$truth" \
  --process-scale 0.1 --walk-std 0.001
estimate dart_alm real/dart_jetracer.zip:car_1_Datarecording_09_16_2024_10_27_02.csv \
  --params data/config/dart_jetracer_single_track.yaml --keep-wheelbase \
  --estimate yaw_inertia_kgm2,cg_to_front_axle_m,max_steer_rad,stall_torque_Nm,no_load_speed_mps,rolling_resistance,tyre.B,tyre.C,tyre.D \
  --measure x,y,yaw,vx,vy,yaw_rate --fit 0:85 --validate 85:105

# The DART sim-vs-real diagnosis (docs/DIAGNOSE.md): report, figures and report.html, written to
# out/, or into results/diagnose/dart with --diagnose-docs (the numbers quoted in docs/DIAGNOSE.md
# and the README come from that report: update them with it).
dart_out="$out/dart"
[ "$diagnose_docs" = 1 ] && dart_out=results/diagnose/dart
echo "[docs_figures] mppi-fit diagnose (DART) -> $dart_out"
"$bin/mppi-fit" diagnose \
  --log data/real/dart_jetracer.zip:car_1_Datarecording_09_16_2024_10_27_02.csv \
  --validate data/real/dart_jetracer.zip:car_1_Datarecording_09_09_2024_16_28_34steering_025_ramp.csv \
  --params data/config/dart_jetracer_single_track.yaml --out "$dart_out" > /dev/null
echo "[docs_figures] done"
