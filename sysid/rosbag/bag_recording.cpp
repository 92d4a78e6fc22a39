#include "sysid/rosbag/bag_recording.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>

#include "base/error.hpp"
#include "sysid/rosbag/bag_file.hpp"

namespace mppi::sysid::bag {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct PoseSample {
  double t, x, y, yaw, roll, pitch, vx, vy, r;
};
struct ControlSample {
  double t, steer, throttle, front_brake, runstop;
};
struct WheelSample {
  double t, lf, rf, lb, rb;
};

std::string base_name(const std::string& path) {
  const auto s = path.find_last_of('/');
  return s == std::string::npos ? path : path.substr(s + 1);
}

// Message time [ns]: the header stamp, or the bag time for a topic whose stamps are zero.
template <class M>
std::vector<std::pair<std::int64_t, M>> decode_topic(const BagFile& bag, const std::string& topic,
                                              M (*decode)(const std::vector<std::uint8_t>&, const std::string&)) {
  std::vector<std::pair<std::int64_t, M>> out;
  std::vector<std::int64_t> receive_ns;
  bool stamped = true;
  bag.for_each_message(topic, [&](std::int64_t received, const std::vector<std::uint8_t>& bytes) {
    M m = decode(bytes, bag.path() + ": topic '" + topic + "' message " + std::to_string(out.size() + 1));
    if (m.header.stamp_ns <= 0) stamped = false;
    receive_ns.push_back(received);
    out.emplace_back(0, std::move(m));
  });
  for (std::size_t i = 0; i < out.size(); ++i) out[i].first = stamped ? out[i].second.header.stamp_ns : receive_ns[i];
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  // Keep strictly increasing times (a repeated stamp keeps its last message).
  std::vector<std::pair<std::int64_t, M>> unique;
  for (auto& s : out) {
    if (!unique.empty() && s.first <= unique.back().first) unique.back() = std::move(s);
    else unique.push_back(std::move(s));
  }
  return unique;
}

double median_interval(const std::vector<double>& t) {
  std::vector<double> d;
  for (std::size_t i = 1; i < t.size(); ++i) d.push_back(t[i] - t[i - 1]);
  if (d.empty()) return 0;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

// Index of the last sample with time <= t (+ a nanosecond for stamps rounded to ns), or -1.
template <class S>
long last_at_or_before(const std::vector<S>& s, double t) {
  const auto it = std::upper_bound(s.begin(), s.end(), t + 1e-9, [](double v, const S& x) { return v < x.t; });
  return static_cast<long>(it - s.begin()) - 1;
}

std::string require_topic(const BagFile& bag, const std::string& key, const std::string& name,
                          const std::string_view type) {
  const std::string topic = bag.resolve(name);
  if (topic.empty())
    throw Error(bag.path() + ": no " + key + " topic '" + name + "' (" + std::string(type) + "); the bag has " +
                bag.topic_list() + " (another name: --topic " + key + "=/TOPIC)");
  return topic;
}

}  // namespace

sim::Recording read_bag_recording(const std::string& path, const BagTopicMap& map) {
  const BagFile bag(path);
  if (map.pose.empty()) throw Error(path + ": the topic map names no pose topic");
  const std::string pose_topic = require_topic(bag, "pose", map.pose, kOdometryType.datatype);
  bag.check_type(pose_topic, kOdometryType);
  const std::string state_topic = bag.resolve(map.chassis_state), command_topic = bag.resolve(map.command);
  std::string controls = map.controls;
  if (controls == "auto") {
    if (!state_topic.empty()) controls = "state";
    else if (!command_topic.empty()) controls = "command";
    else
      throw Error(path + ": no control topic: neither chassis_state '" + map.chassis_state + "' (" +
                  std::string(kChassisStateType.datatype) + ") nor command '" + map.command + "' (" +
                  std::string(kChassisCommandType.datatype) + "); the bag has " + bag.topic_list() +
                  " (other names: --topic chassis_state=/TOPIC or command=/TOPIC)");
  }
  if (controls == "state") require_topic(bag, "chassis_state", map.chassis_state, kChassisStateType.datatype);
  if (controls == "command") require_topic(bag, "command", map.command, kChassisCommandType.datatype);
  if (!state_topic.empty()) bag.check_type(state_topic, kChassisStateType);
  if (!command_topic.empty()) bag.check_type(command_topic, kChassisCommandType);
  const std::string wheel_topic = bag.resolve(map.wheel_speeds);
  if (!wheel_topic.empty()) bag.check_type(wheel_topic, kWheelSpeedsType);

  // Pose -> world pose, body velocity, yaw rate.
  // Times relative to the first pose message (in ns first: stamps near 1.7e9 s keep their ns).
  std::vector<PoseSample> pose;
  std::int64_t t0_ns = 0;
  auto rel = [&t0_ns](std::int64_t ns) { return 1e-9 * static_cast<double>(ns - t0_ns); };
  {
    const auto msgs = decode_topic(bag, pose_topic, &decode_odometry);
    if (!msgs.empty()) t0_ns = msgs.front().first;
    double prev_yaw = 0;
    for (const auto& [ns, m] : msgs) {
      const double t = rel(ns);
      const double qx = m.orientation_xyzw[0], qy = m.orientation_xyzw[1], qz = m.orientation_xyzw[2],
                   qw = m.orientation_xyzw[3];
      double yaw = std::atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz));
      const double roll = std::atan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy));
      const double pitch = std::asin(std::clamp(2 * (qw * qy - qz * qx), -1.0, 1.0));
      if (!pose.empty()) yaw = prev_yaw + std::remainder(yaw - prev_yaw, 2 * std::numbers::pi);
      prev_yaw = yaw;
      double vx = m.linear_mps[0], vy = m.linear_mps[1];
      if (map.twist_frame == "world") {
        const double c = std::cos(yaw), s = std::sin(yaw);
        vx = c * m.linear_mps[0] + s * m.linear_mps[1];
        vy = -s * m.linear_mps[0] + c * m.linear_mps[1];
      }
      pose.push_back({t, m.position_m[0], m.position_m[1], yaw, roll, pitch, vx, vy, m.angular_radps[2]});
    }
  }
  if (pose.size() < 2)
    throw Error(path + ": the pose topic '" + pose_topic + "' holds " + std::to_string(pose.size()) +
                " message(s); a recording needs at least 2");

  // Controls: the chosen source, the command alongside when the source is the chassis state.
  std::vector<ControlSample> ctl, cmd;
  if (!state_topic.empty() && controls == "state")
    for (const auto& [ns, m] : decode_topic(bag, state_topic, &decode_chassis_state))
      ctl.push_back({rel(ns), map.steer_sign * m.steering, m.throttle,
                     m.front_brake >= 0 && m.front_brake <= 1 ? m.front_brake : kNaN,
                     m.runstop_motion_enabled ? 1.0 : 0.0});
  if (!command_topic.empty())
    for (const auto& [ns, m] : decode_topic(bag, command_topic, &decode_chassis_command))
      cmd.push_back({rel(ns), map.steer_sign * m.steering, m.throttle,
                     m.front_brake >= 0 && m.front_brake <= 1 ? m.front_brake : kNaN, kNaN});
  const bool from_state = controls == "state";
  if (!from_state) ctl = cmd;
  if (ctl.empty())
    throw Error(path + ": the control topic '" + (from_state ? state_topic : command_topic) + "' holds no messages");
  std::vector<WheelSample> wheels;
  if (!wheel_topic.empty())
    for (const auto& [ns, m] : decode_topic(bag, wheel_topic, &decode_wheel_speeds))
      wheels.push_back({rel(ns), m.lf_mps, m.rf_mps, m.lb_mps, m.rb_mps});

  // The grid.
  std::vector<double> pose_t;
  for (const auto& p : pose) pose_t.push_back(p.t);
  double rate = map.rate_hz;
  if (!(rate > 0)) {
    const double dt = median_interval(pose_t);
    rate = dt > 0 ? std::max(1.0, std::round(1.0 / dt)) : 50.0;
  }
  const double t0 = pose.front().t, span = pose.back().t - t0;  // t0 = 0
  const std::size_t n = static_cast<std::size_t>(std::floor(span * rate + 1e-6)) + 1;

  std::vector<std::string> columns = {"t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle",
                                      "roll", "pitch", "front_brake"};
  if (from_state) columns.insert(columns.end(), {"runstop_motion_enabled", "command_steer", "command_throttle"});
  if (!wheels.empty())
    columns.insert(columns.end(),
                   {"wheel_speed", "wheel_speed_lf", "wheel_speed_rf", "wheel_speed_lb", "wheel_speed_rb"});
  sim::Recording rec;
  rec.columns = columns;
  rec.data.assign(columns.size(), std::vector<double>(n, kNaN));
  auto col = [&](const char* name) -> std::vector<double>& {
    return rec.data[std::find(columns.begin(), columns.end(), name) - columns.begin()];
  };
  auto& T = col("t");
  auto& X = col("x");
  auto& Y = col("y");
  auto& YAW = col("yaw");
  auto& VX = col("vx");
  auto& VY = col("vy");
  auto& R = col("yaw_rate");
  auto& ROLL = col("roll");
  auto& PITCH = col("pitch");
  auto& STEER = col("steer");
  auto& THROTTLE = col("throttle");
  auto& BRAKE = col("front_brake");
  for (std::size_t k = 0; k < n; ++k) {
    const double t = t0 + static_cast<double>(k) / rate;
    T[k] = static_cast<double>(k) / rate;
    const long i = last_at_or_before(pose, t);
    if (i >= 0) {
      const PoseSample& a = pose[i];
      const PoseSample& b = pose[std::min<std::size_t>(i + 1, pose.size() - 1)];
      const double gap = b.t - a.t;
      if (gap <= map.max_pose_gap_s) {
        const double w = gap > 0 ? std::clamp((t - a.t) / gap, 0.0, 1.0) : 0.0;
        auto lerp = [w](double u, double v) { return u + w * (v - u); };
        X[k] = lerp(a.x, b.x);
        Y[k] = lerp(a.y, b.y);
        YAW[k] = lerp(a.yaw, b.yaw);
        VX[k] = lerp(a.vx, b.vx);
        VY[k] = lerp(a.vy, b.vy);
        R[k] = lerp(a.r, b.r);
        ROLL[k] = lerp(a.roll, b.roll);
        PITCH[k] = lerp(a.pitch, b.pitch);
      }
    }
    const double tc = t + map.command_lead_s;  // the controls' time (BagTopicMap::command_lead_s)
    const long c = last_at_or_before(ctl, tc);
    if (c >= 0 && tc - ctl[c].t <= map.max_command_age_s) {
      STEER[k] = ctl[c].steer;
      THROTTLE[k] = ctl[c].throttle;
      BRAKE[k] = ctl[c].front_brake;
      if (from_state) col("runstop_motion_enabled")[k] = ctl[c].runstop;
    }
    if (from_state) {
      const long m = last_at_or_before(cmd, tc);
      if (m >= 0 && tc - cmd[m].t <= map.max_command_age_s) {
        col("command_steer")[k] = cmd[m].steer;
        col("command_throttle")[k] = cmd[m].throttle;
      }
    }
    if (!wheels.empty()) {
      const long j = last_at_or_before(wheels, t);
      if (j >= 0) {
        const WheelSample& a = wheels[j];
        const WheelSample& b = wheels[std::min<std::size_t>(j + 1, wheels.size() - 1)];
        const double gap = b.t - a.t;
        if (gap <= map.max_pose_gap_s && t - a.t <= map.max_pose_gap_s) {
          const double w = gap > 0 ? std::clamp((t - a.t) / gap, 0.0, 1.0) : 0.0;
          auto lerp = [w](double u, double v) { return u + w * (v - u); };
          const double lf = lerp(a.lf, b.lf), rf = lerp(a.rf, b.rf);
          col("wheel_speed")[k] = 0.5 * (lf + rf);
          col("wheel_speed_lf")[k] = lf;
          col("wheel_speed_rf")[k] = rf;
          col("wheel_speed_lb")[k] = lerp(a.lb, b.lb);
          col("wheel_speed_rb")[k] = lerp(a.rb, b.rb);
        }
      }
    }
  }
  rec.metadata["source"] = "rosbag " + base_name(path);
  rec.metadata["vehicle"] = map.vehicle;
  rec.metadata["rosbag_topics"] = map.describe();
  rec.metadata["controls"] = from_state ? state_topic + " (chassis state)" : command_topic + " (command)";
  char rate_text[32];
  std::snprintf(rate_text, sizeof rate_text, "%g", rate);
  rec.metadata["rate_hz"] = rate_text;
  return rec;
}

}  // namespace mppi::sysid::bag
