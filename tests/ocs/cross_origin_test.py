#!/usr/bin/env python3
"""Only the operator's page drives the car: headless Chromium against mppi-sim --serve.

  cross_origin_test.py BIN_DIR

1. Another site (a second HTTP server, on another port) serves a page that sends a form POST and
   fetches (no-cors, and with a made-up token header) to the control endpoint, asking for
   runstop and a new target speed. Then Chromium asks for the operator page through a foreign
   host name (DNS rebinding: the name resolves to 127.0.0.1).
2. The operator page opened without its token presses RUNSTOP.
After both, the read-only /api/info must show motion still enabled, no target speed requested,
and the requests refused (403, logged by the server).
3. The operator page opened at the printed URL (with the token) presses RUNSTOP and sets a target
speed: both must take effect.
Exit 77 (skipped) when chromium is not installed.
"""
import html
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
from functools import partial
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

from page_launch import Page

T0 = time.time()


def fail(msg):
    print("FAIL: " + msg, flush=True)
    sys.exit(1)


def check(cond, msg):
    if not cond:
        fail(msg)
    print(f"ok ({time.time() - T0:4.1f} s): {msg}", flush=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def chromium_dom(chromium, url, *flags, budget_ms=6000):
    cmd = [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-extensions",
           f"--virtual-time-budget={budget_ms}", *flags, "--dump-dom", url]
    env = dict(os.environ, DBUS_SESSION_BUS_ADDRESS="disabled:")
    return subprocess.run(cmd, capture_output=True, text=True, timeout=60, env=env).stdout


EVIL_PAGE = """<!doctype html><html><body>
<iframe name="sink" style="display:none"></iframe>
<form id="f" method="POST" action="{target}" target="sink">
  <input name="runstop" value="1"><input name="target_speed" value="1.5">
</form>
<pre id="out">pending</pre>
<script>
const target = '{target}', out = [];
document.getElementById('f').submit();
(async () => {{
  const body = () => new URLSearchParams({{ runstop: '1', target_speed: '2.5' }});
  try {{ await fetch(target, {{ method: 'POST', mode: 'no-cors', body: body() }}); out.push('no-cors sent'); }}
  catch (e) {{ out.push('no-cors failed: ' + e.name); }}
  try {{ const r = await fetch(target, {{ method: 'POST', headers: {{ 'X-MPPI-Token': 'guess' }}, body: body() }});
         out.push('cors status ' + r.status); }}
  catch (e) {{ out.push('cors blocked: ' + e.name); }}
  await new Promise((r) => setTimeout(r, 500));  // the form's POST has gone too
  document.getElementById('out').textContent = 'done ' + JSON.stringify(out);
}})();
</script></body></html>
"""


class QuietHandler(SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def page_report(dom):
    m = re.search(r'<pre id="test-report">(.*?)</pre>', dom, re.S)
    return json.loads(html.unescape(m.group(1))) if m else None


def main():
    bin_dir = sys.argv[1]
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if not chromium:
        print("SKIP: chromium is not installed (Debian package chromium)")
        sys.exit(77)
    port = free_port()
    work = tempfile.mkdtemp(prefix="ocs_origin_")
    page = Page([os.path.join(bin_dir, "mppi-sim"), "--serve", str(port), "--max-time", "60", "--laps", "1000",
                 "--samples", "256", "--quiet", "--out", os.path.join(work, "sim")])
    evil_server = None
    try:
        page.wait_ready()
        check(page.url == f"http://127.0.0.1:{port}/?token={page.token}" and len(page.token) == 64,
              f"the page's URL with a 64-digit token is printed: {page.url[:40]}...")
        info = lambda: json.loads(page.http("/api/info", token=False)[1])
        before = info()
        check(before["motion_enabled"] and before["target_speed_mps"] is None and before["refused_requests"] == 0,
              "at start: motion enabled, no target speed requested, nothing refused")

        # ---- 1. another site's page ----
        target = f"http://127.0.0.1:{port}/api/control"
        with open(os.path.join(work, "evil.html"), "w") as f:
            f.write(EVIL_PAGE.format(target=target))
        evil_server = ThreadingHTTPServer(("127.0.0.1", 0), partial(QuietHandler, directory=work))
        threading.Thread(target=evil_server.serve_forever, daemon=True).start()
        evil_origin = f"http://127.0.0.1:{evil_server.server_address[1]}"
        dom = chromium_dom(chromium, f"{evil_origin}/evil.html")
        m = re.search(r'<pre id="out">(.*?)</pre>', dom, re.S)
        check(m and m.group(1).startswith("done"), f"the other site's page ran: {m.group(1) if m else dom[:200]!r}")
        print(f"  its fetches: {html.unescape(m.group(1))}", flush=True)
        after = info()
        check(after["motion_enabled"] is True and after["target_speed_mps"] is None,
              f"after the other site's page: runstop and target speed unchanged ({after})")
        # DNS rebinding: a foreign name for this machine's address reaches the port, but not the page.
        dom = chromium_dom(chromium, f"http://rebound.example:{port}/api/info",
                           "--host-resolver-rules=MAP rebound.example 127.0.0.1", budget_ms=2000)
        check("is not this page" in html.unescape(dom), "a request through a foreign host name is refused (403)")

        # ---- 2. the operator page without its token ----
        dom = chromium_dom(chromium, f"http://127.0.0.1:{port}/?test=1&frames=3&press=runstop",
                           "--window-size=1400,1150")
        report = page_report(dom)
        check(report and report["controls"] and report["controls"][0]["status"] == 403,
              f"the page opened without the token: its RUNSTOP gets 403 ({report and report['controls']})")

        after = info()
        print(f"  /api/info after: {after}", flush=True)
        check(after["motion_enabled"] is True, "runstop unchanged (motion still enabled)")
        check(after["target_speed_mps"] is None, "target speed unchanged (none requested)")
        check(after["refused_requests"] >= 4, f"{after['refused_requests']} requests refused")
        refusals = [l for l in page.lines if l.startswith("ocs: refused")]
        check(any(f"Origin '{evil_origin}'" in l and "POST /api/control" in l for l in refusals),
              "the other site's POST is logged, naming its Origin")
        check(any("Host 'rebound.example" in l for l in refusals), "the foreign host name is logged")

        # ---- 3. the operator page at its printed URL ----
        dom = chromium_dom(chromium, f"{page.url}&test=1&frames=3&press=runstop,set-target&target=4.5",
                           "--window-size=1400,1150")
        report = page_report(dom)
        check(report and [c["status"] for c in report["controls"]] == [200, 200],
              f"the page with its token: RUNSTOP and set target accepted ({report and report['controls']})")
        after = info()
        check(after["motion_enabled"] is False and after["target_speed_mps"] == 4.5,
              f"runstop and target speed changed by the operator's page: {after}")
    finally:
        if evil_server:
            evil_server.shutdown()
        page.proc.kill()  # its log is not needed
        page.proc.wait()
        shutil.rmtree(work, ignore_errors=True)
    print(f"PASS ({time.time() - T0:.1f} s)")


if __name__ == "__main__":
    main()
