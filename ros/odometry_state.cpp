#include "ros/odometry_state.hpp"

#include <cmath>

namespace mppi::ros {

bool state_from_odometry(const OdometryFields& o, VehicleState* state, const char** why) {
  auto fail = [&](const char* what) {
    if (why) *why = what;
    return false;
  };
  if (!std::isfinite(o.x_m) || !std::isfinite(o.y_m)) return fail("pose.position is not finite");
  if (!std::isfinite(o.qw) || !std::isfinite(o.qx) || !std::isfinite(o.qy) || !std::isfinite(o.qz))
    return fail("pose.orientation is not finite");
  const double norm = std::sqrt(o.qw * o.qw + o.qx * o.qx + o.qy * o.qy + o.qz * o.qz);
  if (!(norm > 0.9 && norm < 1.1)) return fail("pose.orientation is not a unit quaternion");
  if (!std::isfinite(o.vx_world_mps) || !std::isfinite(o.vy_world_mps)) return fail("twist.linear is not finite");
  if (!std::isfinite(o.yaw_rate_radps)) return fail("twist.angular.z is not finite");
  const double w = o.qw / norm, x = o.qx / norm, y = o.qy / norm, z = o.qz / norm;
  const double roll = std::atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
  const double yaw = std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
  const double c = std::cos(yaw), s = std::sin(yaw);
  VehicleState v;
  v.x_m = static_cast<float>(o.x_m);
  v.y_m = static_cast<float>(o.y_m);
  v.yaw_rad = static_cast<float>(yaw);
  v.vx_mps = static_cast<float>(c * o.vx_world_mps + s * o.vy_world_mps);
  v.vy_mps = static_cast<float>(-s * o.vx_world_mps + c * o.vy_world_mps);
  v.yaw_rate_radps = static_cast<float>(o.yaw_rate_radps);
  v.roll_rad = static_cast<float>(roll);
  *state = v;
  return true;
}

OdometryFields odometry_from_state(const VehicleState& v, double stamp_s) {
  OdometryFields o;
  o.stamp_s = stamp_s;
  o.x_m = v.x_m;
  o.y_m = v.y_m;
  const double hr = 0.5 * v.roll_rad, hy = 0.5 * v.yaw_rad;  // q = q_yaw * q_roll (pitch 0)
  o.qw = std::cos(hr) * std::cos(hy);
  o.qx = std::sin(hr) * std::cos(hy);
  o.qy = std::sin(hr) * std::sin(hy);
  o.qz = std::cos(hr) * std::sin(hy);
  const double c = std::cos(v.yaw_rad), s = std::sin(v.yaw_rad);
  o.vx_world_mps = c * v.vx_mps - s * v.vy_mps;
  o.vy_world_mps = s * v.vx_mps + c * v.vy_mps;
  o.yaw_rate_radps = v.yaw_rate_radps;
  return o;
}

}  // namespace mppi::ros
