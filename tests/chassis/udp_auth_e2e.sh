#!/bin/bash
# The authenticated link end to end, Python against C++: the simulated chassis
# (mppi-udp-bridge --key) driven by udp_client.py signing with the same key file. Passes when the
# chassis accepted the signed commands, the client got state replies it verified, the same
# traffic unsigned or signed with another key was dropped and counted by reason, and a key file
# readable by others or a bind off loopback without a key was refused by name.
# usage: udp_auth_e2e.sh BIN_DIR SOURCE_DIR
set -u
BIN=$1; SRC=$2
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
PY=/usr/bin/python3
PORT=$((20000 + RANDOM % 20000))
fail() { echo "FAIL: $*"; cat "$OUT"/*.txt 2>/dev/null; exit 1; }
umask 077
head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' > "$OUT/car.key"
head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' > "$OUT/other.key"

"$BIN/mppi-udp-bridge" --port $PORT --key "$OUT/car.key" --duration 4 --quiet > "$OUT/bridge.txt" 2>&1 &
BRIDGE=$!
sleep 0.5
$PY "$SRC/apps/udp_client.py" --port $PORT --key "$OUT/car.key" --throttle 0.3 --seconds 1.5 > "$OUT/signed.txt" 2>&1
$PY "$SRC/apps/udp_client.py" --port $PORT --throttle 0.3 --seconds 0.5 > "$OUT/unsigned.txt" 2>&1
$PY "$SRC/apps/udp_client.py" --port $PORT --key "$OUT/other.key" --throttle 0.3 --seconds 0.5 > "$OUT/other.txt" 2>&1
wait $BRIDGE || fail "mppi-udp-bridge exited with $?"
cat "$OUT/bridge.txt"
accepted=$(sed -n 's/.*commands accepted \([0-9]*\),.*/\1/p' "$OUT/bridge.txt")
no_tag=$(sed -n 's/.*rejected, unauthenticated (no tag): \([0-9]*\)/\1/p' "$OUT/bridge.txt")
bad_tag=$(sed -n 's/.*rejected, bad authentication tag: \([0-9]*\)/\1/p' "$OUT/bridge.txt")
echo "signed commands accepted: ${accepted:-0}, unsigned dropped: ${no_tag:-0}, other key dropped: ${bad_tag:-0}"
[ "${accepted:-0}" -ge 20 ] || fail "the chassis accepted ${accepted:-0} signed commands (expected about 75)"
[ "${no_tag:-0}" -ge 20 ] || fail "unsigned datagrams not counted as unauthenticated"
[ "${bad_tag:-0}" -ge 20 ] || fail "datagrams signed with another key not counted as bad tags"
grep -q "'motion_enabled': True" "$OUT/signed.txt" || fail "the signed client printed no verified state reply"
grep -q "'x'" "$OUT/unsigned.txt" "$OUT/other.txt" && fail "a client without the key got a state reply"

chmod 644 "$OUT/car.key"
"$BIN/mppi-udp-bridge" --port $PORT --key "$OUT/car.key" --duration 1 > "$OUT/mode.txt" 2>&1 && fail "a key file of mode 0644 was used"
grep -q "key file $OUT/car.key has mode 0644; it must not be readable or writable by group or others" "$OUT/mode.txt" \
  || fail "the key file's mode was not named"
$PY "$SRC/apps/udp_client.py" --port $PORT --key "$OUT/car.key" --seconds 0.1 > "$OUT/pymode.txt" 2>&1 \
  && fail "udp_client.py used a key file of mode 0644"
grep -q "has mode 0644" "$OUT/pymode.txt" || fail "udp_client.py did not name the key file's mode"
"$BIN/mppi-udp-bridge" --bind 0.0.0.0 --port $PORT --duration 1 > "$OUT/remote.txt" 2>&1 && fail "bound off loopback without a key"
grep -q "0.0.0.0 is off loopback: it needs a key" "$OUT/remote.txt" || fail "off loopback without a key: no clear refusal"
echo PASS
