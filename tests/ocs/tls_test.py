#!/usr/bin/env python3
"""The operator page over HTTPS, and no plain HTTP off loopback unless asked for.

  tls_test.py BIN_DIR

1. mppi-sim --serve-bind 0.0.0.0 without a certificate refuses to start, naming the choices.
2. With a self-signed certificate (made here with the openssl program) the printed URL is
   https://; the page's status is read over TLS with that certificate as the only trusted one, a
   control with the token is accepted, one without it refused; plain HTTP to the port is no page.
Exit 77 (skipped) without the openssl program.
"""
import json
import os
import shutil
import socket
import ssl
import subprocess
import sys
import tempfile
import urllib.error
import urllib.request

from page_launch import Page


def fail(msg):
    print("FAIL: " + msg, flush=True)
    sys.exit(1)


def check(cond, msg):
    if not cond:
        fail(msg)
    print("ok: " + msg, flush=True)


def main():
    sim = os.path.join(sys.argv[1], "mppi-sim")
    openssl = shutil.which("openssl")
    if not openssl:
        print("SKIP: the openssl program is not installed")
        sys.exit(77)
    work = tempfile.mkdtemp(prefix="ocs_tls_")
    try:
        r = subprocess.run([sim, "--serve", "0", "--serve-bind", "0.0.0.0", "--max-time", "5", "--out",
                            os.path.join(work, "refused")], capture_output=True, text=True, timeout=60)
        check(r.returncode != 0 and "off loopback) over plain HTTP" in r.stderr and "--serve-cert" in r.stderr
              and "--serve-insecure-remote" in r.stderr, f"plain HTTP off loopback refused: {r.stderr.strip()[:160]}")

        cert, key = os.path.join(work, "cert.pem"), os.path.join(work, "key.pem")
        subprocess.run([openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj",
                        "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1", "-keyout", key, "-out", cert],
                       check=True, capture_output=True, timeout=60)
        os.chmod(key, 0o600)
        page = Page([sim, "--serve", "0", "--serve-cert", cert, "--serve-key", key, "--max-time", "60",
                     "--laps", "1000", "--samples", "128", "--quiet", "--out", os.path.join(work, "sim")])
        try:
            check(page.url.startswith("https://127.0.0.1:"), f"the printed URL is https: {page.url[:30]}...")
            base = page.url.split("/?")[0]
            context = ssl.create_default_context(cafile=cert)

            def request(path, data=None, headers=None):
                req = urllib.request.Request(base + path, data=data, headers=headers or {})
                try:
                    with urllib.request.urlopen(req, timeout=10, context=context) as resp:
                        return resp.status, resp.read()
                except urllib.error.HTTPError as e:
                    return e.code, e.read()

            status, body = request("/api/info")
            check(status == 200 and json.loads(body)["mode"] == "live", "status read over TLS")
            check(request("/api/control", b"target_speed=3")[0] == 403, "a control without the token: 403")
            check(request("/api/control", b"target_speed=3", {"X-MPPI-Token": page.token})[0] == 200,
                  "a control with the token: 200")
            check(json.loads(request("/api/info")[1])["target_speed_mps"] == 3.0, "and it took effect")
            port = int(base.rsplit(":", 1)[1])
            with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                s.sendall(f"GET /api/info HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
                try:
                    reply = s.recv(4096)
                except OSError:
                    reply = b""
            check(not reply.startswith(b"HTTP/1.1 200"), "plain HTTP to the TLS port gets no page")
        finally:
            page.proc.kill()
            page.proc.wait()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("PASS")


if __name__ == "__main__":
    main()
