#!/bin/bash
# End to end: the simulated chassis (mppi-udp-bridge), MPPI driving it over UDP
# (mppi-udp-drive), and an operator script that changes the target speed while it drives
# (udp_client.py --set). Passes when the drive program applied the new speed and refused a bad
# parameter by name, and kept driving (completed control ticks after the change).
# usage: udp_parameter_e2e.sh BIN_DIR SOURCE_DIR
set -u
BIN=$1; SRC=$2
OUT=$(mktemp -d)
PORT=$((20000 + RANDOM % 20000)); PARAM_PORT=$((PORT + 1))
"$BIN/mppi-udp-bridge" --port $PORT --duration 8 > "$OUT/bridge.txt" 2>&1 &
BRIDGE=$!
sleep 0.5
"$BIN/mppi-udp-drive" --port $PORT --param-port $PARAM_PORT --model kinematic --samples 256 --horizon 30 \
  --duration 5 > "$OUT/drive.txt" 2> "$OUT/drive.err" &
DRIVE=$!
sleep 2
/usr/bin/python3 "$SRC/apps/udp_client.py" --param-port $PARAM_PORT --set target_speed_mps=7.5
/usr/bin/python3 "$SRC/apps/udp_client.py" --param-port $PARAM_PORT --set no_such_weight=1
wait $DRIVE; RC=$?
kill $BRIDGE 2>/dev/null; wait $BRIDGE 2>/dev/null
cat "$OUT/drive.err" "$OUT/drive.txt"
[ $RC -eq 0 ] || { echo "FAIL: mppi-udp-drive exited with $RC"; exit 1; }
grep -q "target_speed_mps = 7.5 (from OCS)" "$OUT/drive.err" || { echo "FAIL: target speed not applied"; exit 1; }
grep -q "refused: unknown cost parameter 'no_such_weight'" "$OUT/drive.err" || { echo "FAIL: bad parameter not refused by name"; exit 1; }
echo PASS
