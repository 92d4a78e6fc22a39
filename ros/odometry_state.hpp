#pragma once
// nav_msgs/Odometry <-> the controller's common state, on plain fields (no ROS types), so that
// a ROS 1 or ROS 2 node shares it. The convention is AutoRally's state estimator's: the pose in
// the map frame, the linear twist in the map frame (world velocities), angular.z the yaw rate;
// orientation a unit quaternion (w, x, y, z) with roll-pitch-yaw (1-2-3) angles.
#include "mppi/vehicle_state.hpp"

namespace mppi::ros {

struct OdometryFields {
  double stamp_s = 0.0;                      // header.stamp [s]
  double x_m = 0.0, y_m = 0.0, z_m = 0.0;    // pose.pose.position
  double qw = 1.0, qx = 0.0, qy = 0.0, qz = 0.0;  // pose.pose.orientation
  double vx_world_mps = 0.0, vy_world_mps = 0.0, vz_world_mps = 0.0;  // twist.twist.linear
  double roll_rate_radps = 0.0, pitch_rate_radps = 0.0, yaw_rate_radps = 0.0;  // twist.twist.angular
};

// The controller's state: yaw and roll from the quaternion, the world velocity turned into the
// body frame (vx forward, vy left). False (state untouched) when a field is NaN/inf or the
// quaternion is far from unit length (|q| outside [0.9, 1.1]); `why` then names the field.
bool state_from_odometry(const OdometryFields& odom, VehicleState* state, const char** why = nullptr);

// The odometry of a state (pitch 0, height 0) at time stamp_s.
OdometryFields odometry_from_state(const VehicleState& state, double stamp_s);

}  // namespace mppi::ros
