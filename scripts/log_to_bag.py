#!/usr/bin/python3
"""A recording in the project's format (e.g. an mppi-sim log.csv) -> a ROS 1 bag with AutoRally's
topics and message types, as AutoRally's stack would have recorded the drive (docs/ROSBAG.md):

  /pose_estimate   nav_msgs/Odometry: position x, y; orientation from yaw (and roll, pitch where
                   the log has them); twist.linear = the body velocity rotated into the world frame
                   (AutoRally's state estimator); twist.angular.z = yaw_rate
  /chassisCommand  autorally_msgs/chassisCommand: steering = -steer (AutoRally: +1 = right),
                   throttle, frontBrake = -5 (not commanded), sender "mppi_controller"
  /chassisState    autorally_msgs/chassisState: the same steering / throttle as applied by the
                   chassis, commanders "mppi_controller", runstopMotionEnabled true
  /wheelSpeeds     autorally_msgs/wheelSpeeds, all four = wheel_speed (only where the log has it)

Stamps (header and bag time) are START + t. A command is published at the time it was sent: an
mppi-sim log holds in row k+1 the command that produced it (sent at t_k), so with --lead 1 (the
default for `# source: mppi-sim`) row k+1's command is stamped t_k; the last row's is stamped at the
last t as well. AutoRally's message classes are built with genpy from their .msg text (below).

    /usr/bin/python3 scripts/log_to_bag.py LOG.csv OUT.bag [--lead N] [--start S] [--compression none|bz2|lz4]
"""
import argparse
import csv
import math
import sys

import genpy
import genpy.dynamic
import rosbag
from nav_msgs.msg import Odometry

_HEADER = "\n" + "=" * 80 + "\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n"
# autorally_msgs/msg/*.msg as AutoRally defines them.
AUTORALLY_MSG_TEXT = {
    "chassisState": "Header header\n\nbool throttleRelayEnabled\nbool autonomousEnabled\nbool runstopMotionEnabled\n\n"
                    "string steeringCommander\nfloat64 steering\n\nstring throttleCommander\nfloat64 throttle\n\n"
                    "string frontBrakeCommander\nfloat64 frontBrake\n",
    "chassisCommand": "Header header\n\nstring sender\nfloat64 throttle\nfloat64 steering\nfloat64 frontBrake\n",
    "wheelSpeeds": "Header header\nfloat64 lfSpeed\nfloat64 rfSpeed\nfloat64 lbSpeed\nfloat64 rbSpeed\n",
}


def message_class(package, name, text):
    """A genpy message class from .msg text (its dependencies: std_msgs/Header only)."""
    full = f"{package}/{name}"
    return genpy.dynamic.generate_dynamic(full, text + _HEADER)[full]


def autorally_classes():
    return {n: message_class("autorally_msgs", n, t) for n, t in AUTORALLY_MSG_TEXT.items()}


def stamp(start_ns, t_s):
    ns = start_ns + int(round(t_s * 1e9))
    return genpy.Time(ns // 1000000000, ns % 1000000000)


def quaternion(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def read_log(path):
    meta, rows = {}, []
    with open(path, newline="") as f:
        lines = [l for l in f]
    body = []
    for line in lines:
        if line.startswith("#"):
            key, _, value = line[1:].partition(":")
            meta[key.strip()] = value.strip()
        elif line.strip():
            body.append(line)
    reader = csv.DictReader(body)
    for r in reader:
        rows.append({k: (float(v) if v not in ("", None) else math.nan) for k, v in r.items()})
    return meta, rows


def odometry(row, seq, time):
    m = Odometry()
    m.header.seq, m.header.stamp, m.header.frame_id = seq, time, "odom"
    m.child_frame_id = "base_link"
    yaw = row["yaw"]
    roll = row.get("roll", 0.0)
    pitch = row.get("pitch", 0.0)
    roll = 0.0 if math.isnan(roll) else roll
    pitch = 0.0 if math.isnan(pitch) else pitch
    m.pose.pose.position.x, m.pose.pose.position.y = row["x"], row["y"]
    q = quaternion(roll, pitch, yaw)
    (m.pose.pose.orientation.x, m.pose.pose.orientation.y, m.pose.pose.orientation.z,
     m.pose.pose.orientation.w) = q
    c, s = math.cos(yaw), math.sin(yaw)
    m.twist.twist.linear.x = c * row["vx"] - s * row["vy"]
    m.twist.twist.linear.y = s * row["vx"] + c * row["vy"]
    m.twist.twist.angular.z = row["yaw_rate"]
    return m


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("log")
    ap.add_argument("bag")
    ap.add_argument("--lead", type=int, default=None,
                    help="rows between a command's row and the row it was sent at (default: 1 for mppi-sim logs, else 0)")
    ap.add_argument("--start", type=float, default=1.7e9, help="ROS time of t = 0 [s]")
    ap.add_argument("--compression", default="none", choices=["none", "bz2", "lz4"])
    a = ap.parse_args(argv)
    meta, rows = read_log(a.log)
    if not rows:
        sys.exit(f"{a.log}: no rows")
    lead = a.lead if a.lead is not None else (1 if meta.get("source") == "mppi-sim" else 0)
    msgs = autorally_classes()
    start_ns = int(round(a.start * 1e9))
    has_wheels = "wheel_speed" in rows[0]
    with rosbag.Bag(a.bag, "w", compression=a.compression) as bag:
        for k, row in enumerate(rows):
            if any(math.isnan(row[c]) for c in ("x", "y", "yaw", "vx", "vy", "yaw_rate")):
                continue
            t = stamp(start_ns, row["t"])
            bag.write("/pose_estimate", odometry(row, k, t), t)
            if has_wheels and not math.isnan(row["wheel_speed"]):
                w = msgs["wheelSpeeds"]()
                w.header.seq, w.header.stamp = k, t
                w.lfSpeed = w.rfSpeed = w.lbSpeed = w.rbSpeed = row["wheel_speed"]
                bag.write("/wheelSpeeds", w, t)
        for k in range(len(rows)):
            src = rows[min(k + lead, len(rows) - 1)]
            if math.isnan(src["steer"]) or math.isnan(src["throttle"]):
                continue
            t = stamp(start_ns, rows[k]["t"])
            c = msgs["chassisCommand"]()
            c.header.seq, c.header.stamp, c.header.frame_id = k, t, "mppi_controller"
            c.sender, c.steering, c.throttle, c.frontBrake = "mppi_controller", -src["steer"], src["throttle"], -5.0
            bag.write("/chassisCommand", c, t)
            s = msgs["chassisState"]()
            s.header.seq, s.header.stamp = k, t
            s.throttleRelayEnabled = s.autonomousEnabled = s.runstopMotionEnabled = True
            s.steeringCommander = s.throttleCommander = "mppi_controller"
            s.frontBrakeCommander = ""
            s.steering, s.throttle, s.frontBrake = -src["steer"], src["throttle"], 0.0
            bag.write("/chassisState", s, t)
    print(f"wrote {a.bag}: {len(rows)} rows, command lead {lead}")


if __name__ == "__main__":
    main(sys.argv[1:])
