#!/usr/bin/env bash
# Screenshots of the operator page for the docs: the live page after FRAMES frames of a simulation
# at 6 m/s, and a replay of that run's log. Usage: scripts/ocs_screenshots.sh [BIN_DIR] [FRAMES]
set -euo pipefail
bin=${1:-build/bin}
frames=${2:-300}
out=docs/results
work=$(mktemp -d)
shot() {  # URL PNG
  DBUS_SESSION_BUS_ADDRESS=disabled: chromium --headless --no-sandbox --disable-gpu --no-first-run \
    --window-size=1400,1150 --virtual-time-budget=60000 --screenshot="$PWD/$2" "$1" >/dev/null 2>&1
}
page_url() {  # LOG: the page's URL with its token, as the server printed it
  until grep -qo 'http://127\.0\.0\.1:[0-9]*/?token=[0-9a-f]*' "$1" 2>/dev/null; do sleep 0.2; done
  grep -o 'http://127\.0\.0\.1:[0-9]*/?token=[0-9a-f]*' "$1" | head -n 1
}
port=$((20000 + RANDOM % 20000))
"$bin/mppi-sim" --serve "$port" --laps 1000 --max-time 300 --out "$work/live" --quiet 2>"$work/live.err" &
sim=$!
url=$(page_url "$work/live.err")
until curl -sf "http://127.0.0.1:$port/api/info" >/dev/null; do sleep 0.2; done
shot "$url&frames=$frames" "$out/ocs_live.png"
curl -sf -X POST -H "X-MPPI-Token: ${url##*token=}" -d stop=1 "http://127.0.0.1:$port/api/control" >/dev/null
wait "$sim" || true
"$bin/mppi-sim" --replay "$work/live/log.csv" --serve "$((port + 1))" 2>"$work/replay.err" &
replay=$!
url=$(page_url "$work/replay.err")
until curl -sf "http://127.0.0.1:$((port + 1))/api/info" >/dev/null; do sleep 0.2; done
shot "$url" "$out/ocs_replay.png"
kill "$replay"
wait "$replay" || true
rm -rf "$work"
echo "wrote $out/ocs_live.png $out/ocs_replay.png"
