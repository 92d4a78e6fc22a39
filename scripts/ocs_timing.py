#!/usr/bin/env python3
"""Optimizer time with and without the operator page connected, in one run.

  scripts/ocs_timing.py [--bin build/bin] [--seconds 120] [--cycle 5] [--out out/ocs_timing] [-- SIM ARGS]

Starts `mppi-sim --serve` (real time) and one headless Chromium that keeps the page open for the
whole run; the page connects to the frame stream for `cycle` seconds, then disconnects for `cycle`
seconds, and so on, so both conditions share the same minutes of machine load. mppi-sim splits
the optimizer times by whether a page was connected during the step and writes
OUT/ocs_timing.json (p50, p99 and the with/without ratios), printed at the end.
"""
import argparse
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
import urllib.request


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default="build/bin")
    ap.add_argument("--seconds", type=float, default=120)
    ap.add_argument("--cycle", type=float, default=5)
    ap.add_argument("--out", default="out/ocs_timing")
    ap.add_argument("--client", choices=["chromium", "stream"], default="chromium",
                    help="chromium: the page in a headless browser on this machine; stream: a reader of the "
                         "frame stream that draws nothing (the server's own cost)")
    ap.add_argument("--browser-idle", action="store_true",
                    help="run Chromium under SCHED_IDLE (chrt --idle 0), as one would on the car's own computer")
    ap.add_argument("sim_args", nargs="*")
    a = ap.parse_args()
    chromium = shutil.which("chromium")
    if not chromium:
        sys.exit("ocs_timing: chromium is not installed")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    sim = subprocess.Popen([os.path.join(a.bin, "mppi-sim"), "--serve", str(port), "--laps", "100000",
                            "--max-time", str(a.seconds * 10), "--out", a.out, "--quiet", *a.sim_args],
                           stderr=subprocess.PIPE, text=True)
    token = page_token(sim)
    url = f"http://127.0.0.1:{port}"
    for _ in range(300):
        try:
            urllib.request.urlopen(url + "/api/info", timeout=2)
            break
        except OSError:
            time.sleep(0.2)
    if a.client == "stream":
        stream_cycles(port, a.seconds, a.cycle)
    else:
        browse(chromium, f"{url}/?token={token}", a.seconds, a.cycle, a.browser_idle)
    urllib.request.urlopen(urllib.request.Request(url + "/api/control", data=b"stop=1",
                                                  headers={"X-MPPI-Token": token}), timeout=10)
    sim.wait(timeout=120)
    print(json.dumps(json.load(open(os.path.join(a.out, "ocs_timing.json"))), indent=2))


def page_token(sim):
    """The page's token, from the URL mppi-sim prints; its stderr is then passed on to ours."""
    token = None
    for line in sim.stderr:
        sys.stderr.write(line)
        m = re.search(r"/\?token=([0-9a-f]+)", line)
        if m:
            token = m.group(1)
            break
    threading.Thread(target=lambda: [sys.stderr.write(l) for l in sim.stderr], daemon=True).start()
    if not token:
        sys.exit("ocs_timing: mppi-sim printed no page URL")
    return token


def stream_cycles(port, seconds, cycle):
    """Reads /api/stream for `cycle` seconds, then stays away for `cycle` seconds, and so on."""
    end = time.time() + seconds
    while time.time() < end:
        with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
            s.sendall(f"GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
            until = time.time() + cycle
            while time.time() < until:
                try:
                    s.recv(1 << 20)
                except socket.timeout:
                    pass
        time.sleep(cycle)


def browse(chromium, url, seconds, cycle, idle):
    env = dict(os.environ, DBUS_SESSION_BUS_ADDRESS="disabled:")
    # a browser that stays on the page until we end it (a DevTools port keeps headless Chromium open)
    prefix = ["chrt", "--idle", "0"] if idle else []
    browser = subprocess.Popen([*prefix, chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                                "--window-size=1400,1150", "--remote-debugging-port=0",
                                f"{url}&cycle={cycle}"], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    time.sleep(seconds)
    browser.terminate()
    browser.wait(timeout=60)


if __name__ == "__main__":
    main()
