#!/usr/bin/env python3
"""A minimal stack speaking the chassis UDP format (docs/CHASSIS.md) with only the standard
library: it allows motion as runstop source 'OCS', sends a constant command as controller
'joystick' at 50 Hz for a few seconds, prints the chassis' state replies, then stops the car.

    build/bin/mppi-udp-bridge &          # the vehicle end (simulated car)
    python3 apps/udp_client.py --steering 0.3 --throttle 0.2 --seconds 3

With --set NAME=VALUE it instead sends one parameter message to a running stack (mppi-udp-drive
listens on --param-port, 47801 by default), e.g. a new target speed:

    python3 apps/udp_client.py --set target_speed_mps=8
"""
import argparse
import socket
import struct
import time
import zlib

MAGIC, VERSION = b"MPCH", 1
COMMAND, RUNSTOP, STATE, PARAMETER = 1, 2, 3, 4
HEADER = struct.Struct("<4sBBHQ16s")            # magic, version, type, length, sequence, sender
COMMAND_BODY = struct.Struct("<fffB3x")          # steering, throttle, front_brake, actuators
RUNSTOP_BODY = struct.Struct("<B3x")             # motion_enabled
STATE_BODY = struct.Struct("<d7f3f3HBx")         # time, state[7], applied[3], pulses[3], flags
PARAMETER_BODY = struct.Struct("<32sd")          # name (NUL-padded), value


def message(kind, sender, sequence, body):
    length = HEADER.size + len(body) + 4
    head = HEADER.pack(MAGIC, VERSION, kind, length, sequence, sender.encode("ascii"))
    return head + body + struct.pack("<I", zlib.crc32(head + body))  # zlib's CRC-32 = the format's


def parse_state(data):
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
    a = p.parse_args()
    if a.set:
        name, _, value = a.set.partition("=")
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        body = PARAMETER_BODY.pack(name.encode("ascii"), float(value))
        sock.sendto(message(PARAMETER, "OCS", int(time.time() * 1e6), body), (a.host, a.param_port))
        return
    chassis = (a.host, a.port)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.settimeout(0.005)
    sequence = int(time.time() * 1e6)  # strictly increasing per sender, also across restarts
    end = time.monotonic() + a.seconds
    last_print = 0.0
    while time.monotonic() < end:
        sequence += 1
        sock.sendto(message(RUNSTOP, "OCS", sequence, RUNSTOP_BODY.pack(1)), chassis)
        sequence += 1
        body = COMMAND_BODY.pack(a.steering, a.throttle, 0.0, 0b111)
        sock.sendto(message(COMMAND, "joystick", sequence, body), chassis)
        try:
            while True:
                state = parse_state(sock.recv(256))
                if state and time.monotonic() - last_print > 0.5:
                    last_print = time.monotonic()
                    print(state)
        except socket.timeout:
            pass
        time.sleep(0.02)
    sequence += 1
    sock.sendto(message(RUNSTOP, "OCS", sequence, RUNSTOP_BODY.pack(0)), chassis)


if __name__ == "__main__":
    main()
