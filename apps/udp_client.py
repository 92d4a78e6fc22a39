#!/usr/bin/env python3
"""A minimal stack speaking the chassis UDP format (docs/CHASSIS.md) with only the standard
library: it allows motion as runstop source 'OCS', sends a constant command as controller
'joystick' at 50 Hz for a few seconds, prints the chassis' state replies, then stops the car.

    build/bin/mppi-udp-bridge &          # the vehicle end (simulated car)
    python3 apps/udp_client.py --steering 0.3 --throttle 0.2 --seconds 3

With --set NAME=VALUE it instead sends one parameter message to a running stack (mppi-udp-drive
listens on --param-port, 47801 by default), e.g. a new target speed:

    python3 apps/udp_client.py --set target_speed_mps=8

With --key FILE (the vehicle's key: 64 hex digits, mode 600) every datagram carries an
HMAC-SHA256 tag and only state replies with the right tag are printed (docs/CHASSIS.md,
"Authentication"); a chassis started with --key drops datagrams without one.
"""
import argparse
import hashlib
import hmac
import os
import socket
import stat
import struct
import sys
import time
import zlib

MAGIC, VERSION = b"MPCH", 1
COMMAND, RUNSTOP, STATE, PARAMETER = 1, 2, 3, 4
HEADER = struct.Struct("<4sBBHQ16s")            # magic, version, type, length, sequence, sender
COMMAND_BODY = struct.Struct("<fffB3x")          # steering, throttle, front_brake, actuators
RUNSTOP_BODY = struct.Struct("<B3x")             # motion_enabled
STATE_BODY = struct.Struct("<d7f3f3HBx")         # time, state[7], applied[3], pulses[3], flags
PARAMETER_BODY = struct.Struct("<32sd")          # name (NUL-padded), value
TAG_SIZE = 32                                    # HMAC-SHA256


def load_key(path):
    """The key in `path`: 64 hex digits. Refused, like the C++ ends do, when group or others may
    read or write the file."""
    mode = os.stat(path).st_mode
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        sys.exit(f"key file {path} has mode {stat.S_IMODE(mode):04o}; it must not be readable or writable by "
                 f"group or others (chmod 600 {path})")
    with open(path) as f:
        text = f.read().strip()
    if len(text) != 64:
        sys.exit(f"key file {path}: expected a key of 64 hex digits (32 bytes), got {len(text)} characters")
    return bytes.fromhex(text)


def message(kind, sender, sequence, body, key=None):
    """One datagram: header | body | CRC-32, then with a key the HMAC-SHA256 tag of all of that."""
    length = HEADER.size + len(body) + 4
    head = HEADER.pack(MAGIC, VERSION, kind, length, sequence, sender.encode("ascii"))
    m = head + body + struct.pack("<I", zlib.crc32(head + body))  # zlib's CRC-32 = the format's
    return m + hmac.new(key, m, hashlib.sha256).digest() if key else m


def parse_state(data, key=None):
    if key:  # the tag first: nothing of a datagram without the right one is read
        m, tag = data[:-TAG_SIZE], data[-TAG_SIZE:]
        if len(data) <= TAG_SIZE or not hmac.compare_digest(tag, hmac.new(key, m, hashlib.sha256).digest()):
            return None
        data = m
    if len(data) != HEADER.size + STATE_BODY.size + 4:
        return None
    if struct.unpack("<I", data[-4:])[0] != zlib.crc32(data[:-4]):
        return None
    magic, version, kind, length, sequence, sender = HEADER.unpack_from(data)
    if magic != MAGIC or version != VERSION or kind != STATE:
        return None
    v = STATE_BODY.unpack_from(data, HEADER.size)
    return {"t": v[0], "x": v[1], "y": v[2], "vx": v[4], "pulses_us": v[11:14],
            "motion_enabled": bool(v[14] & 1), "watchdog": bool(v[14] & 2)}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=47800)
    p.add_argument("--steering", type=float, default=0.0)
    p.add_argument("--throttle", type=float, default=0.2)
    p.add_argument("--seconds", type=float, default=3.0)
    p.add_argument("--set", metavar="NAME=VALUE", help="send one parameter message to the stack and exit")
    p.add_argument("--param-port", type=int, default=47801)
    p.add_argument("--key", metavar="FILE", help="sign datagrams with this key file (required off loopback)")
    a = p.parse_args()
    key = load_key(a.key) if a.key else None
    if key is None and not a.host.startswith("127."):
        sys.exit(f"{a.host} is off loopback: the link there needs a key (--key FILE)")
    if a.set:
        name, _, value = a.set.partition("=")
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        body = PARAMETER_BODY.pack(name.encode("ascii"), float(value))
        sock.sendto(message(PARAMETER, "OCS", int(time.time() * 1e6), body, key), (a.host, a.param_port))
        return
    chassis = (a.host, a.port)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.settimeout(0.005)
    sequence = int(time.time() * 1e6)  # strictly increasing per sender, also across restarts
    end = time.monotonic() + a.seconds
    last_print = 0.0
    while time.monotonic() < end:
        sequence += 1
        sock.sendto(message(RUNSTOP, "OCS", sequence, RUNSTOP_BODY.pack(1), key), chassis)
        sequence += 1
        body = COMMAND_BODY.pack(a.steering, a.throttle, 0.0, 0b111)
        sock.sendto(message(COMMAND, "joystick", sequence, body, key), chassis)
        try:
            while True:
                state = parse_state(sock.recv(256), key)
                if state and time.monotonic() - last_print > 0.5:
                    last_print = time.monotonic()
                    print(state)
        except socket.timeout:
            pass
        time.sleep(0.02)
    sequence += 1
    sock.sendto(message(RUNSTOP, "OCS", sequence, RUNSTOP_BODY.pack(0), key), chassis)


if __name__ == "__main__":
    main()
