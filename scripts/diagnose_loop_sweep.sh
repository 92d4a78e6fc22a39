#!/usr/bin/env bash
# Closing the loop for every effect of the sweep: for each hidden effect (large size), diagnose
# the sweep's seed-1 recording, then race MPPI with the nominal model against MPPI with the
# corrected model on a plant that has the effect (seeds 1..N). Prints one Markdown table.
#   scripts/diagnose_loop_sweep.sh SWEEP_DIR [OUT_DIR] [SEEDS]
# SWEEP_DIR: the --out of `mppi-fit diagnose sweep` (its recordings are reused).
set -euo pipefail
sweep=${1:?usage: $0 SWEEP_DIR [OUT_DIR] [SEEDS]}
out=${2:-out/diagnose_loop_sweep}
seeds=${3:-3}
fit=${MPPI_FIT:-build/bin/mppi-fit}
mkdir -p "$out"
echo "| hidden effect (large) | named | controller | seeds finishing | 3-lap time [s] | crashes | mean \|v - v_target\| [m/s] |"
echo "|---|---|---|---|---|---|---|"
for id in aero_drag rolling_resistance steer_delay throttle_delay steer_lag throttle_lag steer_offset steer_gain \
          throttle_offset tire_saturation friction_change load_transfer motor_voltage_sag road_grade; do
  rec="$sweep/${id}_large_s1.csv"
  [[ -f $rec ]] || { echo "missing $rec (run the sweep first)" >&2; exit 1; }
  mkdir -p "$out/$id"
  "$fit" diagnose --log "$rec" --out "$out/$id/diagnosis" --no-plots > "$out/$id/diagnose.txt"
  named=$(sed -n 's/^selected: //p' "$out/$id/diagnose.txt" | tr ' ' '+')
  "$fit" diagnose loop --case "$id:large" --model-params "$out/$id/diagnosis/corrected_model.yaml" \
    --samples 512 --laps 3 --speed 8 --seeds "$seeds" --out "$out/$id/loop" > "$out/$id/loop.md"
  # The two summary rows (after the second table header).
  awk -v id="$id" -v named="$named" '/seeds finishing all laps/ {t = 1; next} t && /^\| (nominal|corrected)/ {
      sub(/^\| /, ""); print "| " id " | " named " | " $0 }' "$out/$id/loop.md"
done
