#pragma once
// Which topics of a rosbag hold the drive, and how their values map to the recording format
// (docs/ROSBAG.md). The defaults are AutoRally's topics and conventions; another stack names its
// own with a YAML file (--topic-map FILE.yaml) or KEY=VALUE pairs (--topic pose=/odom,...).
#include <string>
#include <vector>

namespace mppi::sysid::bag {

struct BagTopicMap {
  std::string pose = "/pose_estimate";            // nav_msgs/Odometry
  std::string chassis_state = "/chassisState";    // autorally_msgs/chassisState ("" = none)
  std::string command = "/chassisCommand";        // autorally_msgs/chassisCommand ("" = none)
  std::string wheel_speeds = "/wheelSpeeds";      // autorally_msgs/wheelSpeeds ("" = none)
  // Where steer / throttle come from: "state" (what the chassis applied, chassisState), "command"
  // (what the controller sent, chassisCommand) or "auto" (state when the bag has it, else command).
  std::string controls = "auto";
  // Frame of the Odometry twist's linear part: "world" (AutoRally's state estimator publishes the
  // velocity in the odometry frame) or "body" (REP-105: child_frame_id).
  std::string twist_frame = "world";
  double steer_sign = -1;  // recording steer = steer_sign * message steering (AutoRally: +1 = right)
  double rate_hz = 0;      // grid of the recording; 0 = the pose topic's median rate, rounded
  double max_pose_gap_s = 0.1;    // pose samples further apart than this leave the rows between missing
  double max_command_age_s = 0.5; // a command older than this leaves steer / throttle missing
  // Row k holds the latest control message at or before t_k + command_lead_s. 0: the command in
  // force at t_k. A controller that answers each pose within a few ms (stamping its command when it
  // sends it) has sent its answer to pose k just after t_k; with a lead of half a row that answer is
  // row k's, the command acting over (t_k, t_k+1] as the diagnosis reads it.
  double command_lead_s = 0.0;
  std::string vehicle = "autorally";  // the recording's `vehicle` metadata

  // Throws mppi::Error naming `where` and the key for an unknown key or a bad value.
  void set(const std::string& key, const std::string& value, const std::string& where);
  // "k=v,k=v" (the --topic option).
  void apply_pairs(const std::string& text);
  // A YAML mapping of the same keys (the --topic-map option); errors name the file.
  void apply_yaml_file(const std::string& path);
  // "pose=/pose_estimate,..." for the recording's metadata.
  std::string describe() const;
};

// The keys set() knows, for messages and the documentation.
std::vector<std::string> topic_map_keys();

}  // namespace mppi::sysid::bag
