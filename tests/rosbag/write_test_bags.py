#!/usr/bin/python3
"""Rosbags for the rosbag import's tests, written with python3-rosbag (independent of the C++
reader): a closed-form drive and bags that must be refused.

    write_test_bags.py OUT_DIR

circle.bag     4 s at 2 m/s on a circle of radius 4 m (yaw rate 0.5 rad/s), AutoRally's topics as
               `rosbag record` writes them (caller ids, /chassisState latched), stamps from 1.7e9 s:
               /pose_estimate 100 Hz at i * 0.01 s (twist in the world frame)
               /chassisCommand 50 Hz at 0.005 + 0.02 j: steering -0.3, throttle 0.1 + 0.001 j, frontBrake -5
               /chassisState   50 Hz at 0.007 + 0.02 j: steering -0.25, throttle 0.2 + 0.001 j,
                               frontBrake 0.1, runstopMotionEnabled while j < 100
               /wheelSpeeds   100 Hz: lf 1.9, rf 2.1, lb 1.8, rb 2.2
circle_lz4.bag the same, lz4-compressed chunks; circle_bz2.bag bz2
other_stack.bag the same drive as /odom (twist in the body frame) and /cmd (chassisCommand) only
namespaced.bag  the drive with /autorally_platform/chassisState and /autorally_platform/wheelSpeeds
no_controls.bag /pose_estimate and /wheelSpeeds only
no_pose.bag     /chassisCommand and /chassisState only
wrong_type.bag  /pose_estimate as geometry_msgs/PoseStamped
old_state.bag   /chassisState of an older definition (no throttleRelayEnabled / autonomousEnabled)
"""
import math
import os
import sys

import genpy
import rosbag
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from log_to_bag import autorally_classes, message_class  # noqa: E402

START_NS = 1700000000 * 1000000000
V, R = 2.0, 4.0
W = V / R
DURATION = 4.0


def stamp(t):
    ns = START_NS + int(round(t * 1e9))
    return genpy.Time(ns // 1000000000, ns % 1000000000)


def odom(t, seq, world_twist=True):
    m = Odometry()
    m.header.seq, m.header.stamp, m.header.frame_id = seq, stamp(t), "odom"
    m.child_frame_id = "base_link"
    yaw = W * t
    m.pose.pose.position.x, m.pose.pose.position.y = R * math.sin(yaw), R * (1 - math.cos(yaw))
    m.pose.pose.orientation.z, m.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    if world_twist:
        m.twist.twist.linear.x, m.twist.twist.linear.y = V * math.cos(yaw), V * math.sin(yaw)
    else:
        m.twist.twist.linear.x = V
    m.twist.twist.angular.z = W
    return m


def record_header(topic, msg, callerid, latching="0"):
    """The connection header `rosbag record` stores: the publisher's, with its caller id and latching."""
    return {"topic": topic, "type": msg._type, "md5sum": msg._md5sum, "message_definition": msg._full_text,
            "callerid": callerid, "latching": latching}


def write_drive(path, msgs, compression="none", pose_topic="/pose_estimate", command_topic="/chassisCommand",
                state_topic="/chassisState", wheel_topic="/wheelSpeeds", world_twist=True):
    with rosbag.Bag(path, "w", compression=compression) as bag:
        for i in range(int(round(DURATION * 100)) + 1):
            t = i * 0.01
            if pose_topic:
                m = odom(t, i, world_twist)
                bag.write(pose_topic, m, stamp(t), connection_header=record_header(pose_topic, m, "/state_estimator"))
            if wheel_topic:
                w = msgs["wheelSpeeds"]()
                w.header.seq, w.header.stamp = i, stamp(t)
                w.lfSpeed, w.rfSpeed, w.lbSpeed, w.rbSpeed = 1.9, 2.1, 1.8, 2.2
                bag.write(wheel_topic, w, stamp(t))
        for j in range(int(DURATION * 50)):
            if command_topic:
                tc = 0.005 + 0.02 * j
                c = msgs["chassisCommand"]()
                c.header.seq, c.header.stamp = j, stamp(tc)
                c.sender, c.steering, c.throttle, c.frontBrake = "mppi_controller", -0.3, 0.1 + 0.001 * j, -5.0
                bag.write(command_topic, c, stamp(tc), connection_header=record_header(command_topic, c, "/mppi_controller"))
            if state_topic:
                ts = 0.007 + 0.02 * j
                s = msgs["chassisState"]()
                s.header.seq, s.header.stamp = j, stamp(ts)
                s.throttleRelayEnabled = s.autonomousEnabled = True
                s.runstopMotionEnabled = j < 100
                s.steeringCommander = s.throttleCommander = s.frontBrakeCommander = "mppi_controller"
                s.steering, s.throttle, s.frontBrake = -0.25, 0.2 + 0.001 * j, 0.1
                bag.write(state_topic, s, stamp(ts), connection_header=record_header(state_topic, s, "/chassis", "1"))


def main(out):
    os.makedirs(out, exist_ok=True)
    msgs = autorally_classes()
    write_drive(os.path.join(out, "circle.bag"), msgs)
    write_drive(os.path.join(out, "circle_lz4.bag"), msgs, compression="lz4")
    write_drive(os.path.join(out, "circle_bz2.bag"), msgs, compression="bz2")
    write_drive(os.path.join(out, "other_stack.bag"), msgs, pose_topic="/odom", command_topic="/cmd", state_topic="",
                wheel_topic="", world_twist=False)
    write_drive(os.path.join(out, "namespaced.bag"), msgs, command_topic="", state_topic="/autorally_platform/chassisState",
                wheel_topic="/autorally_platform/wheelSpeeds")
    write_drive(os.path.join(out, "no_controls.bag"), msgs, command_topic="", state_topic="")
    write_drive(os.path.join(out, "no_pose.bag"), msgs, pose_topic="", wheel_topic="")
    with rosbag.Bag(os.path.join(out, "wrong_type.bag"), "w") as bag:
        for i in range(10):
            p = PoseStamped()
            p.header.stamp = stamp(0.01 * i)
            bag.write("/pose_estimate", p, stamp(0.01 * i))
            c = msgs["chassisCommand"]()
            c.header.stamp = stamp(0.01 * i)
            bag.write("/chassisCommand", c, stamp(0.01 * i))
    old = message_class("autorally_msgs", "chassisState",
                        "Header header\nbool runstopMotionEnabled\nstring steeringCommander\nfloat64 steering\n"
                        "string throttleCommander\nfloat64 throttle\nstring frontBrakeCommander\nfloat64 frontBrake\n")
    with rosbag.Bag(os.path.join(out, "old_state.bag"), "w") as bag:
        for i in range(10):
            bag.write("/pose_estimate", odom(0.01 * i, i), stamp(0.01 * i))
            s = old()
            s.header.stamp = stamp(0.01 * i)
            bag.write("/chassisState", s, stamp(0.01 * i))


if __name__ == "__main__":
    main(sys.argv[1])
