#pragma once
// A rosbag of a drive -> the project's recording format (docs/ROSBAG.md, docs/RECORDING_FORMAT.md).
//   t                       grid at `rate_hz` (default: the pose topic's median rate) from the first
//                           pose to the last; message time = header stamp (the bag time where a
//                           topic's stamps are zero)
//   x, y, yaw, roll, pitch  Odometry pose, linearly interpolated (yaw unwrapped first)
//   vx, vy                  Odometry twist.linear, rotated by -yaw into the body frame when
//                           twist_frame is "world" (AutoRally), as published when "body"
//   yaw_rate                Odometry twist.angular.z
//   steer, throttle         chassisState (controls "state") or chassisCommand ("command"), the
//                           latest message at or before t, held; steer = steer_sign * steering
//   front_brake             the same message's frontBrake where in [0, 1]
//   runstop_motion_enabled  chassisState (1 / 0), held
//   command_steer, command_throttle  chassisCommand, held, when the controls come from chassisState
//   wheel_speed             mean of the front wheels (undriven), wheel_speed_lf/rf/lb/rb [m/s]
// Rows where a pose pair is further apart than max_pose_gap_s, or a command older than
// max_command_age_s (or none yet), leave those values missing (empty fields).
#include <string>

#include "sim/recording.hpp"
#include "sysid/rosbag/bag_topic_map.hpp"

namespace mppi::sysid::bag {

// Throws mppi::Error naming the file: not a readable bag; a needed topic missing (naming it and
// listing the bag's topics); a topic of the wrong type; a message that does not decode.
sim::Recording read_bag_recording(const std::string& path, const BagTopicMap& map = {});

}  // namespace mppi::sysid::bag
