#!/usr/bin/env python3
"""The operator page in a real browser (headless Chromium), against a running simulation and a replay.

  browser_test.py BIN_DIR OUT_DIR

1. mppi-sim --serve: bad requests (garbage bytes, unknown paths, bad control values, an oversized
   body, too many streams), stream clients that disconnect mid-stream, a pause; then Chromium loads
   the page, which reports the frames it got and counts the car, plan and rollout colours on its
   map canvas, and hands over the canvas as a PNG; this script decodes the PNG itself and counts
   again. Then the run is stopped and driven again without a server: the logs must agree row for
   row (the page, the bad requests and the pause did not change what the controller did).
2. mppi-sim --replay on that log: the page shows the car and its trail at the slider's time.
Canvas PNGs are saved in OUT_DIR. Exit 77 (skipped) when chromium is not installed.
"""
import base64
import csv
import html
import json
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
import zlib

from page_launch import Page

SAMPLES = "512"
TOKENS = {}  # port -> the page's token, read from the URL the server printed


def fail(msg):
    print("FAIL: " + msg, flush=True)
    sys.exit(1)


T0 = time.time()


def check(cond, msg):
    if not cond:
        fail(msg)
    print(f"ok ({time.time() - T0:4.0f} s): {msg}", flush=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def http(port, path, data=None, timeout=10):
    req = urllib.request.Request(f"http://127.0.0.1:{port}{path}", data=data,
                                 headers={"X-MPPI-Token": TOKENS.get(port, "")})
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


def wait_ready(port, proc, seconds=60):
    end = time.time() + seconds
    while time.time() < end:
        if proc.poll() is not None:
            fail(f"server exited early with {proc.returncode}")
        try:
            if http(port, "/api/info", timeout=2)[0] == 200:
                return
        except OSError:
            pass
        time.sleep(0.2)
    fail("server did not answer /api/info")


def raw(port, payload, read=True):
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(payload)
        return s.recv(4096) if read else b""


def stream_events(port, count, timeout=20):
    """Opens /api/stream, reads `count` events and disconnects mid-stream."""
    s = socket.create_connection(("127.0.0.1", port), timeout=timeout)
    s.sendall(f"GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
    buf, events = b"", []
    end = time.time() + timeout
    while len(events) < count and time.time() < end:
        chunk = s.recv(65536)
        if not chunk:
            break
        buf += chunk
        events = re.findall(rb"data: (\{.*?\})\n\n", buf, re.S)
    s.close()
    return [json.loads(e) for e in events[:count]]


def png_pixels(data):
    """Decodes an 8-bit RGB/RGBA non-interlaced PNG: (width, height, channels, bytes)."""
    check(data[:8] == b"\x89PNG\r\n\x1a\n", "canvas is a PNG")
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour not in (2, 6) or interlace:
                fail(f"unexpected PNG format depth {depth} colour {colour} interlace {interlace}")
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw_rows = zlib.decompress(idat)
    stride = width * channels
    out, prev = bytearray(), bytearray(stride)
    for y in range(height):
        f = raw_rows[y * (stride + 1)]
        line = bytearray(raw_rows[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if f == 1:
            for i in range(channels, stride):
                line[i] = (line[i] + line[i - channels]) & 255
        elif f == 2:
            for i in range(stride):
                line[i] = (line[i] + prev[i]) & 255
        elif f == 3:
            for i in range(stride):
                left = line[i - channels] if i >= channels else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
        elif f == 4:
            for i in range(stride):
                a = line[i - channels] if i >= channels else 0
                b, c = prev[i], prev[i - channels] if i >= channels else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        out += line
        prev = line
    return width, height, channels, bytes(out)


def count_colours(png):
    """Pixels of the car (magenta), the plan (white), rollouts (cyan..yellow), trail (green..red)."""
    w, h, ch, px = png_pixels(png)
    ramp = lambda a, b: [tuple(round(a[k] + (b[k] - a[k]) * s / 20) for k in range(3)) for s in range(21)]
    rollout_ramp = ramp((0, 200, 255), (255, 230, 0))
    trail_ramp = ramp((0, 180, 0), (230, 0, 0))
    near = lambda p, c, tol: abs(p[0] - c[0]) + abs(p[1] - c[1]) + abs(p[2] - c[2]) <= tol
    counts = {"car": 0, "plan": 0, "rollout": 0, "trail": 0}
    for o in range(0, w * h * ch, ch):
        p = px[o:o + 3]
        if p[0] == p[1] == p[2]:
            if p[0] >= 250:
                counts["plan"] += 1
            continue  # grey: the track and cost map
        if near(p, (255, 0, 255), 10):
            counts["car"] += 1
        elif any(near(p, c, 12) for c in rollout_ramp):
            counts["rollout"] += 1
        elif any(near(p, c, 12) for c in trail_ramp):
            counts["trail"] += 1
    return counts


def browser_report(chromium, url, save_png):
    cmd = [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
           "--disable-extensions", "--window-size=1400,1150", "--virtual-time-budget=8000",
           "--dump-dom", url]
    env = dict(os.environ, DBUS_SESSION_BUS_ADDRESS="disabled:")
    dom = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env).stdout
    m = re.search(r'<pre id="test-report">(.*?)</pre>', dom, re.S)
    if not m:
        fail(f"the page did not report (no frames?) for {url}; DOM head: {dom[:300]!r}")
    report = json.loads(html.unescape(m.group(1)))
    png = base64.b64decode(report.pop("canvas_png").split(",", 1)[1])
    with open(save_png, "wb") as f:
        f.write(png)
    print(f"page report: {report}", flush=True)
    return report, count_colours(png)


def read_log(path):
    with open(path) as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    return rows[0], rows[1:]


def main():
    bin_dir, out_dir = sys.argv[1], sys.argv[2]
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if not chromium:
        print("SKIP: chromium is not installed (Debian package chromium)")
        sys.exit(77)
    os.makedirs(out_dir, exist_ok=True)
    sim = os.path.join(bin_dir, "mppi-sim")
    work = tempfile.mkdtemp(prefix="ocs_test_")
    started = time.time()

    # ---- 1. live ----
    port = free_port()
    live_dir = os.path.join(work, "live")
    page = Page([sim, "--serve", str(port), "--max-time", "120", "--laps", "1000", "--samples", SAMPLES,
                 "--out", live_dir, "--quiet"])
    proc = page.proc
    TOKENS[port] = page.token
    try:
        wait_ready(port, proc)
        info = json.loads(http(port, "/api/info")[1])
        check(info["mode"] == "live" and info["has_track"], "live mode with a track")
        # bad requests
        raw(port, b"\x00\xff\x13GARBAGE\r\n\r\n")
        raw(port, b"GET /" + b"a" * 20000 + b" HTTP/1.1\r\n\r\n")
        raw(port, b"GET /api/info HTTP/1.1\r\n", read=False)  # an unfinished request, then gone
        check(http(port, "/no/such/page")[0] == 404, "unknown path: 404")
        for body, what in [(b"target_speed=abc", "target_speed"), (b"target_speed=nan", "target_speed"),
                           (b"target_speed=99", "target_speed"), (b"runstop=2", "runstop"),
                           (b"warp=1", "warp"), (b"", "no parameter")]:
            status, reply = http(port, "/api/control", data=body)
            check(status == 400 and what in json.loads(reply)["error"], f"control {body!r}: 400 naming {what}")
        status, _ = http(port, "/api/control", data=b"target_speed=" + b"1" * 200000)
        check(status == 413, "oversized body: 413")
        # streams that go away mid-stream, and one stream too many
        for _ in range(3):
            events = stream_events(port, 2)
            check(len(events) == 2 and events[1]["t"] > events[0]["t"], "a stream client got 2 frames and left")
        def wait_clients(predicate):
            end = time.time() + 20
            while not predicate(json.loads(http(port, "/api/info")[1])["clients"]) and time.time() < end:
                time.sleep(0.1)
        wait_clients(lambda n: n == 0)  # the streams that left are noticed at the next frame
        holders = []
        for _ in range(4):
            s = socket.create_connection(("127.0.0.1", port), timeout=5)
            s.sendall(f"GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
            holders.append(s)
        wait_clients(lambda n: n >= 4)
        fifth = raw(port, f"GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
        check(fifth.startswith(b"HTTP/1.1 503"), "a fifth stream: 503")
        for s in holders:
            s.close()
        # pause holds the simulation
        check(http(port, "/api/control", data=b"pause=1")[0] == 200, "pause accepted")
        time.sleep(0.3)
        check(json.loads(http(port, "/api/info")[1])["paused"], "paused")
        time.sleep(1.0)
        http(port, "/api/control", data=b"pause=0")
        after = stream_events(port, 2)
        check(len(after) == 2 and after[1]["t"] > after[0]["t"], "running again after pause")

        report, pixels = browser_report(chromium, f"{page.url}&test=1",
                                        os.path.join(out_dir, "ocs_live_canvas.png"))
        print(f"canvas PNG decoded here: {pixels}", flush=True)
        check(report["mode"] == "live" and report["frames"] >= 15, "the page got 15 frames")
        check(report["uplot"] and report["charts"] == 6, "uPlot loaded, 6 strip charts")
        check(report["rollouts_in_frame"] == 63, "63 rollouts in a frame")
        check(pixels["car"] >= 60 and report["car_pixels"] >= 60, "the car is drawn (magenta pixels)")
        check(pixels["rollout"] >= 300 and report["rollout_pixels"] >= 300, "rollouts are drawn (weight colours)")
        check(pixels["plan"] >= 60, "the plan is drawn (white pixels)")
        check(abs(pixels["car"] - report["car_pixels"]) <= 0.05 * report["car_pixels"] + 5,
              "the page's own car count agrees with the decoded PNG")
        http(port, "/api/control", data=b"stop=1")
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            fail("the simulation did not stop on request")
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            proc.wait(timeout=30)
    check(os.path.exists(os.path.join(live_dir, "ocs_timing.json")), "timing split written")
    print(json.load(open(os.path.join(live_dir, "ocs_timing.json"))), flush=True)

    # the same run without a server must drive exactly the same
    header, served = read_log(os.path.join(live_dir, "log.csv"))
    check(len(served) > 100, f"served run logged {len(served)} steps")
    ref_dir = os.path.join(work, "reference")
    last_t = float(served[-1][0])
    subprocess.run([sim, "--max-time", f"{last_t:.6f}", "--laps", "1000", "--samples", SAMPLES, "--out", ref_dir,
                    "--quiet"], check=False, timeout=300)
    _, reference = read_log(os.path.join(ref_dir, "log.csv"))
    n = min(len(served), len(reference))
    # every column but the wall-clock optimizer time
    keep = [k for k, c in enumerate(header) if c != "optimizer_ms"]
    diff = [i for i in range(n) if [served[i][k] for k in keep] != [reference[i][k] for k in keep]]
    check(n >= len(served) - 1 and not diff,
          f"served and reference runs agree on all {n} steps (first difference: {diff[:1]})")

    # ---- 2. replay of a recording ----
    # A recording of its own, 8 simulated seconds (the live run's log holds only the few seconds
    # the checks above took in real time: too short a trail to count its pixels reliably).
    replay_dir = os.path.join(work, "replay_source")
    # (exit status 1: the laps asked for were not all driven in the time given; the log is whole)
    subprocess.run([sim, "--max-time", "8", "--laps", "1000", "--samples", SAMPLES, "--out", replay_dir, "--quiet"],
                   check=False, timeout=300)
    check(os.path.exists(os.path.join(replay_dir, "log.csv")), "a recording to replay")
    port2 = free_port()
    replay_page = Page([sim, "--replay", os.path.join(replay_dir, "log.csv"), "--serve", str(port2)])
    replay = replay_page.proc
    TOKENS[port2] = replay_page.token
    try:
        wait_ready(port2, replay)
        check(json.loads(http(port2, "/api/info")[1])["mode"] == "replay", "replay mode")
        check(http(port2, "/api/control", data=b"pause=1")[0] == 404, "a replay has no controls: 404")
        report, pixels = browser_report(chromium, f"{replay_page.url}&test=1",
                                        os.path.join(out_dir, "ocs_replay_canvas.png"))
        print(f"canvas PNG decoded here: {pixels}", flush=True)
        check(report["mode"] == "replay", "the page replays")
        check(pixels["car"] >= 60, "the car is drawn in the replay")
        check(pixels["trail"] >= 200, "the trail is drawn in the replay (speed colours)")
    finally:
        replay.send_signal(signal.SIGTERM)
        try:
            replay.wait(timeout=20)
        except subprocess.TimeoutExpired:
            replay.kill()
            fail("the replay server did not stop on SIGTERM")
    check(replay.returncode == 0, "replay server stopped cleanly")
    shutil.rmtree(work, ignore_errors=True)
    print(f"PASS ({time.time() - started:.0f} s)")


if __name__ == "__main__":
    main()
