"""Starts a program that serves the operator page and reads the page's URL, with its token, from
what the program prints ("ocs: operator page on http://127.0.0.1:PORT/?token=..."). Shared by
the browser tests; Python 3 standard library only."""
import re
import subprocess
import threading
import time
import urllib.error
import urllib.request

URL_LINE = re.compile(r"ocs: (?:operator page|replay of .*) on (https?://[^/\s]+/\?token=([0-9a-f]+))")


class Page:
    """A running server: proc, url, token, and every line it wrote to stderr (in .lines)."""

    def __init__(self, cmd, seconds=60):
        self.proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
        self.lines, self.url, self.token = [], None, None
        self._found = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()
        if not self._found.wait(seconds):
            self.proc.kill()
            raise RuntimeError(f"no page URL printed by {cmd[0]} in {seconds} s; it wrote: {self.lines[-5:]}")

    def _read(self):
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))
            m = URL_LINE.search(line)
            if m and not self._found.is_set():
                self.url, self.token = m.group(1), m.group(2)
                self._found.set()
        self._found.set()  # the program ended without one: __init__ reports it

    def http(self, path, data=None, headers=None, token=True, timeout=10):
        """(status, body) of a request to the page's own host; with the token unless token=False."""
        base = self.url.split("/?")[0]
        h = dict(headers or {})
        if token:
            h.setdefault("X-MPPI-Token", self.token)
        req = urllib.request.Request(base + path, data=data, headers=h)
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                return r.status, r.read()
        except urllib.error.HTTPError as e:
            return e.code, e.read()

    def wait_ready(self, seconds=60):
        end = time.time() + seconds
        while time.time() < end:
            if self.proc.poll() is not None:
                raise RuntimeError(f"server exited early with {self.proc.returncode}")
            try:
                if self.http("/api/info", timeout=2)[0] == 200:
                    return
            except OSError:
                pass
            time.sleep(0.2)
        raise RuntimeError("server did not answer /api/info")
