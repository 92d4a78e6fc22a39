#pragma once
// The nodes' ROS 1 message conversions (C++17, header-only): nav_msgs/Odometry <-> the plain
// odometry fields (ros/odometry_state.hpp), the planned path as nav_msgs/Path and the feedback
// gains as std_msgs/Float32MultiArray. Inside namespace mppi::ros, ROS's own namespace is ::ros.
#include <cstddef>
#include <string>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/time.h>
#include <std_msgs/Float32MultiArray.h>

#include "ros/odometry_state.hpp"

namespace mppi::ros {

inline OdometryFields fields_of(const nav_msgs::Odometry& m) {
  OdometryFields o;
  o.stamp_s = m.header.stamp.toSec();
  o.x_m = m.pose.pose.position.x;
  o.y_m = m.pose.pose.position.y;
  o.z_m = m.pose.pose.position.z;
  o.qw = m.pose.pose.orientation.w;
  o.qx = m.pose.pose.orientation.x;
  o.qy = m.pose.pose.orientation.y;
  o.qz = m.pose.pose.orientation.z;
  o.vx_world_mps = m.twist.twist.linear.x;
  o.vy_world_mps = m.twist.twist.linear.y;
  o.vz_world_mps = m.twist.twist.linear.z;
  o.roll_rate_radps = m.twist.twist.angular.x;
  o.pitch_rate_radps = m.twist.twist.angular.y;
  o.yaw_rate_radps = m.twist.twist.angular.z;
  return o;
}

// The odometry message of a state, stamped `stamp`, in frame `frame_id` (child base_link).
inline nav_msgs::Odometry odometry_msg(const VehicleState& state, const ::ros::Time& stamp, const std::string& frame_id) {
  const OdometryFields o = odometry_from_state(state, stamp.toSec());
  nav_msgs::Odometry m;
  m.header.stamp = stamp;
  m.header.frame_id = frame_id;
  m.child_frame_id = "base_link";
  m.pose.pose.position.x = o.x_m;
  m.pose.pose.position.y = o.y_m;
  m.pose.pose.position.z = o.z_m;
  m.pose.pose.orientation.w = o.qw;
  m.pose.pose.orientation.x = o.qx;
  m.pose.pose.orientation.y = o.qy;
  m.pose.pose.orientation.z = o.qz;
  m.twist.twist.linear.x = o.vx_world_mps;
  m.twist.twist.linear.y = o.vy_world_mps;
  m.twist.twist.angular.z = o.yaw_rate_radps;
  return m;
}

// A path of (x, y) points, one every dt_s from `stamp`, in frame `frame_id`.
inline nav_msgs::Path path_msg(const std::vector<float>& xy, double dt_s, const ::ros::Time& stamp,
                               const std::string& frame_id) {
  nav_msgs::Path path;
  path.header.stamp = stamp;
  path.header.frame_id = frame_id;
  path.poses.resize(xy.size() / 2);
  for (std::size_t i = 0; i < path.poses.size(); ++i) {
    auto& p = path.poses[i];
    p.header.stamp = stamp + ::ros::Duration(static_cast<double>(i) * dt_s);
    p.header.frame_id = frame_id;
    p.pose.position.x = xy[2 * i];
    p.pose.position.y = xy[2 * i + 1];
    p.pose.orientation.w = 1.0;
  }
  return path;
}

// Gains T x nu x nx (row-major) with the dimensions labelled t, control, state.
inline std_msgs::Float32MultiArray gains_msg(const std::vector<float>& gains, int horizon, int nu, int nx) {
  std_msgs::Float32MultiArray g;
  g.layout.dim.resize(3);
  const int sizes[3] = {horizon, nu, nx};
  const char* labels[3] = {"t", "control", "state"};
  unsigned stride = static_cast<unsigned>(horizon * nu * nx);
  for (int d = 0; d < 3; ++d) {
    g.layout.dim[static_cast<std::size_t>(d)].label = labels[d];
    g.layout.dim[static_cast<std::size_t>(d)].size = static_cast<unsigned>(sizes[d]);
    g.layout.dim[static_cast<std::size_t>(d)].stride = stride;
    stride /= static_cast<unsigned>(sizes[d]);
  }
  g.data = gains;
  return g;
}

}  // namespace mppi::ros
