#pragma once
// The common state layout every vehicle model of the library starts with, so that costs,
// the simulator and the logs read any model's state the same way. Models append their
// own extra states (wheel speeds, ...) after index kCommonStates - 1.
// Frames: ISO 8855 / REP-103 (x forward, y left, yaw counter-clockwise positive).
#include <array>

namespace mppi {

namespace state {
inline constexpr int kX = 0;        // world x [m]
inline constexpr int kY = 1;        // world y [m]
inline constexpr int kYaw = 2;      // heading [rad], CCW positive, unwrapped
inline constexpr int kVx = 3;       // body longitudinal velocity [m/s]
inline constexpr int kVy = 4;       // body lateral velocity [m/s], left positive
inline constexpr int kYawRate = 5;  // [rad/s], CCW positive
inline constexpr int kRoll = 6;     // [rad], right side down positive (ISO)
inline constexpr int kCommonStates = 7;
}  // namespace state

namespace control {
inline constexpr int kSteer = 0;     // normalised steering in [-1, 1], positive turns left
inline constexpr int kThrottle = 1;  // normalised throttle in [-1, 1], negative brakes
inline constexpr int kCommonControls = 2;
}  // namespace control

// One vehicle's common state, for APIs that take a single state (not a batch).
struct VehicleState {
  float x_m = 0.f;
  float y_m = 0.f;
  float yaw_rad = 0.f;
  float vx_mps = 0.f;
  float vy_mps = 0.f;
  float yaw_rate_radps = 0.f;
  float roll_rad = 0.f;

  std::array<float, state::kCommonStates> to_array() const {
    return {x_m, y_m, yaw_rad, vx_mps, vy_mps, yaw_rate_radps, roll_rad};
  }
  static VehicleState from_array(const float* s) {
    return {s[0], s[1], s[2], s[3], s[4], s[5], s[6]};
  }
};

struct Control {
  float steer = 0.f;     // [-1, 1], positive left
  float throttle = 0.f;  // [-1, 1], negative brakes
};

}  // namespace mppi
