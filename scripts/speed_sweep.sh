#!/usr/bin/env bash
# The controller's quality curve: MPPI on the AutoRally network drives the (calibrated)
# single-track plant at target speeds from 6 to 12 m/s on the three tracks; per run the mean
# speed, best and median lap, crashes and peak body slip angle. Writes OUT/<track>_<speed>/
# (mppi-sim's log.csv, track.png, track_slip.png, summary.json), then OUT/SPEED_SWEEP.md
# (table) and OUT/speed_sweep.svg (plot) with scripts/speed_sweep_report.py.
#   scripts/speed_sweep.sh [OUT_DIR]
# Environment: SPEEDS ("6 7 8 9 10 11 12"), TRACKS ("gazebo marietta ccrf"), LAPS (10),
# SEED (1), SAMPLES (1920), MPPI_SIM (build/bin/mppi-sim); extra mppi-sim options in SIM_ARGS.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/speed_sweep}
speeds=${SPEEDS:-"6 7 8 9 10 11 12"}
tracks=${TRACKS:-"gazebo marietta ccrf"}
laps=${LAPS:-10}
seed=${SEED:-1}
samples=${SAMPLES:-1920}
sim=${MPPI_SIM:-build/bin/mppi-sim}
[[ -x $sim ]] || { echo "$sim not found: build the mppi-sim target first" >&2; exit 1; }
mkdir -p "$out"
for track in $tracks; do
  for v in $speeds; do
    run="$out/${track}_${v}"
    if [[ -f $run/summary.json ]]; then echo "keeping $run (delete it to re-run)"; continue; fi
    echo "== $track at $v m/s, $laps laps, seed $seed"
    # mppi-sim exits 1 when the run stops before its laps; the summary still records it.
    "$sim" --track "$track" --speed "$v" --laps "$laps" --seed "$seed" --samples "$samples" \
      --out "$run" --quiet ${SIM_ARGS:-} || true
  done
done
/usr/bin/python3 scripts/speed_sweep_report.py "$out" > "$out/SPEED_SWEEP.md"
echo "wrote $out/SPEED_SWEEP.md and $out/speed_sweep.svg"
