#pragma once
// The ROS 1 messages a drive is read from, as plain structs decoded from their serialised bytes
// (no generated message headers: AutoRally's types are not installed as C++ headers, and the
// bytes of a rosbag are all that is needed). Layouts and md5 sums:
//   nav_msgs/Odometry            header, child_frame_id, pose (position, orientation, 6x6
//                                covariance), twist (linear, angular, 6x6 covariance)
//   autorally_msgs/chassisState  header, throttleRelayEnabled, autonomousEnabled,
//                                runstopMotionEnabled (bool = 1 byte), steeringCommander, steering,
//                                throttleCommander, throttle, frontBrakeCommander, frontBrake
//   autorally_msgs/chassisCommand header, sender, throttle, steering, frontBrake
//   autorally_msgs/wheelSpeeds   header, lfSpeed, rfSpeed, lbSpeed, rbSpeed [m/s]
// std_msgs/Header = uint32 seq, time stamp (uint32 sec, uint32 nsec), string frame_id; a string
// is a uint32 length and its bytes; float64 little-endian.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace mppi::sysid::bag {

// A message type as a rosbag connection names it.
struct MessageType {
  std::string_view datatype;
  std::string_view md5sum;
};
inline constexpr MessageType kOdometryType{"nav_msgs/Odometry", "cd5e73d190d741a2f92e81eda573aca7"};
inline constexpr MessageType kChassisStateType{"autorally_msgs/chassisState", "cbd23a33a5ec266cc70ab1630ddbccef"};
inline constexpr MessageType kChassisCommandType{"autorally_msgs/chassisCommand",
                                                 "aba3aba8fc9c485b4f2735439447f458"};
inline constexpr MessageType kWheelSpeedsType{"autorally_msgs/wheelSpeeds", "c5c4a96a4e17d91e72a2f7397af4d720"};

struct Header {
  std::uint32_t seq = 0;
  std::int64_t stamp_ns = 0;  // sec * 1e9 + nsec; 0 = not stamped
  std::string frame_id;
};

struct Odometry {
  Header header;
  std::string child_frame_id;
  double position_m[3] = {0, 0, 0};
  double orientation_xyzw[4] = {0, 0, 0, 1};
  double linear_mps[3] = {0, 0, 0};     // twist.linear, in the frame the publisher uses
  double angular_radps[3] = {0, 0, 0};  // twist.angular
};

struct ChassisState {
  Header header;
  bool throttle_relay_enabled = false, autonomous_enabled = false, runstop_motion_enabled = false;
  std::string steering_commander, throttle_commander, front_brake_commander;
  double steering = 0, throttle = 0, front_brake = 0;  // normalised, AutoRally's signs
};

struct ChassisCommand {
  Header header;
  std::string sender;
  double throttle = 0, steering = 0, front_brake = 0;  // frontBrake < 0: not commanded
};

struct WheelSpeeds {
  Header header;
  double lf_mps = 0, rf_mps = 0, lb_mps = 0, rb_mps = 0;
};

// Decoders. Each throws mppi::Error "<what>: ..." when the bytes end early or trail the message.
Odometry decode_odometry(const std::vector<std::uint8_t>& bytes, const std::string& what);
ChassisState decode_chassis_state(const std::vector<std::uint8_t>& bytes, const std::string& what);
ChassisCommand decode_chassis_command(const std::vector<std::uint8_t>& bytes, const std::string& what);
WheelSpeeds decode_wheel_speeds(const std::vector<std::uint8_t>& bytes, const std::string& what);

}  // namespace mppi::sysid::bag
