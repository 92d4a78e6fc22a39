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

// The topics the recording is read from (empty: not in the bag), their types checked, and where
// the controls come from: "state" (the chassis state) or "command".
struct Topics {
  std::string pose, state, command, wheels, controls;
};

Topics resolve_topics(const BagFile& bag, const BagTopicMap& map) {
  const std::string& path = bag.path();
  if (map.pose.empty()) throw Error(path + ": the topic map names no pose topic");
  Topics t;
  t.pose = require_topic(bag, "pose", map.pose, kOdometryType.datatype);
  bag.check_type(t.pose, kOdometryType);
  t.state = bag.resolve(map.chassis_state);
  t.command = bag.resolve(map.command);
  t.controls = map.controls;
  if (t.controls == "auto") {
    if (!t.state.empty()) t.controls = "state";
    else if (!t.command.empty()) t.controls = "command";
    else
      throw Error(path + ": no control topic: neither chassis_state '" + map.chassis_state + "' (" +
                  std::string(kChassisStateType.datatype) + ") nor command '" + map.command + "' (" +
                  std::string(kChassisCommandType.datatype) + "); the bag has " + bag.topic_list() +
                  " (other names: --topic chassis_state=/TOPIC or command=/TOPIC)");
  }
  if (t.controls == "state") require_topic(bag, "chassis_state", map.chassis_state, kChassisStateType.datatype);
  if (t.controls == "command") require_topic(bag, "command", map.command, kChassisCommandType.datatype);
  if (!t.state.empty()) bag.check_type(t.state, kChassisStateType);
  if (!t.command.empty()) bag.check_type(t.command, kChassisCommandType);
  t.wheels = bag.resolve(map.wheel_speeds);
  if (!t.wheels.empty()) bag.check_type(t.wheels, kWheelSpeedsType);
  return t;
}

// Every topic's samples, in seconds after the first pose message (in ns first: stamps near
// 1.7e9 s keep their ns).
struct Samples {
  std::vector<PoseSample> pose;
  std::vector<ControlSample> controls, commands;  // the chosen source; the command alongside a state
  std::vector<WheelSample> wheels;
};

// Pose -> world pose, body velocity, yaw rate; sets t0_ns to the first message's time.
std::vector<PoseSample> read_poses(const BagFile& bag, const std::string& topic, const BagTopicMap& map,
                                   std::int64_t& t0_ns) {
  std::vector<PoseSample> pose;
  const auto msgs = decode_topic(bag, topic, &decode_odometry);
  if (!msgs.empty()) t0_ns = msgs.front().first;
  double prev_yaw = 0;
  for (const auto& [ns, m] : msgs) {
    const double t = 1e-9 * static_cast<double>(ns - t0_ns);
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
  if (pose.size() < 2)
    throw Error(bag.path() + ": the pose topic '" + topic + "' holds " + std::to_string(pose.size()) +
                " message(s); a recording needs at least 2");
  return pose;
}

Samples read_samples(const BagFile& bag, const BagTopicMap& map, const Topics& topics) {
  Samples s;
  std::int64_t t0_ns = 0;
  s.pose = read_poses(bag, topics.pose, map, t0_ns);
  auto rel = [t0_ns](std::int64_t ns) { return 1e-9 * static_cast<double>(ns - t0_ns); };
  if (!topics.state.empty() && topics.controls == "state")
    for (const auto& [ns, m] : decode_topic(bag, topics.state, &decode_chassis_state))
      s.controls.push_back({rel(ns), map.steer_sign * m.steering, m.throttle,
                            m.front_brake >= 0 && m.front_brake <= 1 ? m.front_brake : kNaN,
                            m.runstop_motion_enabled ? 1.0 : 0.0});
  if (!topics.command.empty())
    for (const auto& [ns, m] : decode_topic(bag, topics.command, &decode_chassis_command))
      s.commands.push_back({rel(ns), map.steer_sign * m.steering, m.throttle,
                            m.front_brake >= 0 && m.front_brake <= 1 ? m.front_brake : kNaN, kNaN});
  const bool from_state = topics.controls == "state";
  if (!from_state) s.controls = s.commands;
  if (s.controls.empty())
    throw Error(bag.path() + ": the control topic '" + (from_state ? topics.state : topics.command) +
                "' holds no messages");
  if (!topics.wheels.empty())
    for (const auto& [ns, m] : decode_topic(bag, topics.wheels, &decode_wheel_speeds))
      s.wheels.push_back({rel(ns), m.lf_mps, m.rf_mps, m.lb_mps, m.rb_mps});
  return s;
}

// The grid's rate: the map's, or the pose messages' median rate rounded to whole hertz.
double grid_rate_hz(const BagTopicMap& map, const std::vector<PoseSample>& pose) {
  if (map.rate_hz > 0) return map.rate_hz;
  std::vector<double> pose_t;
  for (const auto& p : pose) pose_t.push_back(p.t);
  const double dt = median_interval(pose_t);
  return dt > 0 ? std::max(1.0, std::round(1.0 / dt)) : 50.0;
}

// The recording's columns, every value NaN over n rows.
sim::Recording empty_grid(bool from_state, bool wheels, std::size_t n) {
  std::vector<std::string> columns = {"t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle",
                                      "roll", "pitch", "front_brake"};
  if (from_state) columns.insert(columns.end(), {"runstop_motion_enabled", "command_steer", "command_throttle"});
  if (wheels)
    columns.insert(columns.end(),
                   {"wheel_speed", "wheel_speed_lf", "wheel_speed_rf", "wheel_speed_lb", "wheel_speed_rb"});
  sim::Recording rec;
  rec.columns = columns;
  rec.data.assign(columns.size(), std::vector<double>(n, kNaN));
  return rec;
}

std::vector<double>& column(sim::Recording& rec, const char* name) {
  return rec.data[std::find(rec.columns.begin(), rec.columns.end(), name) - rec.columns.begin()];
}

// Row k of the grid at time t: the pose interpolated between its messages (not across a gap).
void fill_pose(const std::vector<PoseSample>& pose, const BagTopicMap& map, double t, std::size_t k,
               sim::Recording& rec) {
  const long i = last_at_or_before(pose, t);
  if (i < 0) return;
  const PoseSample& a = pose[i];
  const PoseSample& b = pose[std::min<std::size_t>(i + 1, pose.size() - 1)];
  const double gap = b.t - a.t;
  if (!(gap <= map.max_pose_gap_s)) return;
  const double w = gap > 0 ? std::clamp((t - a.t) / gap, 0.0, 1.0) : 0.0;
  auto lerp = [w](double u, double v) { return u + w * (v - u); };
  column(rec, "x")[k] = lerp(a.x, b.x);
  column(rec, "y")[k] = lerp(a.y, b.y);
  column(rec, "yaw")[k] = lerp(a.yaw, b.yaw);
  column(rec, "vx")[k] = lerp(a.vx, b.vx);
  column(rec, "vy")[k] = lerp(a.vy, b.vy);
  column(rec, "yaw_rate")[k] = lerp(a.r, b.r);
  column(rec, "roll")[k] = lerp(a.roll, b.roll);
  column(rec, "pitch")[k] = lerp(a.pitch, b.pitch);
}

// Row k: the last controls (and commands, beside a chassis state) at the controls' time tc, unless older
// than max_command_age_s.
void fill_controls(const Samples& s, const BagTopicMap& map, bool from_state, double tc, std::size_t k,
                   sim::Recording& rec) {
  const long c = last_at_or_before(s.controls, tc);
  if (c >= 0 && tc - s.controls[c].t <= map.max_command_age_s) {
    column(rec, "steer")[k] = s.controls[c].steer;
    column(rec, "throttle")[k] = s.controls[c].throttle;
    column(rec, "front_brake")[k] = s.controls[c].front_brake;
    if (from_state) column(rec, "runstop_motion_enabled")[k] = s.controls[c].runstop;
  }
  if (from_state) {
    const long m = last_at_or_before(s.commands, tc);
    if (m >= 0 && tc - s.commands[m].t <= map.max_command_age_s) {
      column(rec, "command_steer")[k] = s.commands[m].steer;
      column(rec, "command_throttle")[k] = s.commands[m].throttle;
    }
  }
}

// Row k: the wheel speeds interpolated between their messages (not across a gap, nor after a stale one).
void fill_wheels(const std::vector<WheelSample>& wheels, const BagTopicMap& map, double t, std::size_t k,
                 sim::Recording& rec) {
  const long j = last_at_or_before(wheels, t);
  if (j < 0) return;
  const WheelSample& a = wheels[j];
  const WheelSample& b = wheels[std::min<std::size_t>(j + 1, wheels.size() - 1)];
  const double gap = b.t - a.t;
  if (!(gap <= map.max_pose_gap_s && t - a.t <= map.max_pose_gap_s)) return;
  const double w = gap > 0 ? std::clamp((t - a.t) / gap, 0.0, 1.0) : 0.0;
  auto lerp = [w](double u, double v) { return u + w * (v - u); };
  const double lf = lerp(a.lf, b.lf), rf = lerp(a.rf, b.rf);
  column(rec, "wheel_speed")[k] = 0.5 * (lf + rf);
  column(rec, "wheel_speed_lf")[k] = lf;
  column(rec, "wheel_speed_rf")[k] = rf;
  column(rec, "wheel_speed_lb")[k] = lerp(a.lb, b.lb);
  column(rec, "wheel_speed_rb")[k] = lerp(a.rb, b.rb);
}

}  // namespace

sim::Recording read_bag_recording(const std::string& path, const BagTopicMap& map) {
  const BagFile bag(path);
  const Topics topics = resolve_topics(bag, map);
  const Samples s = read_samples(bag, map, topics);
  const bool from_state = topics.controls == "state";
  const double rate = grid_rate_hz(map, s.pose);
  const double t0 = s.pose.front().t, span = s.pose.back().t - t0;  // t0 = 0
  const std::size_t n = static_cast<std::size_t>(std::floor(span * rate + 1e-6)) + 1;
  sim::Recording rec = empty_grid(from_state, !s.wheels.empty(), n);
  std::vector<double>& T = column(rec, "t");
  for (std::size_t k = 0; k < n; ++k) {
    const double t = t0 + static_cast<double>(k) / rate;
    T[k] = static_cast<double>(k) / rate;
    fill_pose(s.pose, map, t, k, rec);
    fill_controls(s, map, from_state, t + map.command_lead_s, k, rec);  // BagTopicMap::command_lead_s
    if (!s.wheels.empty()) fill_wheels(s.wheels, map, t, k, rec);
  }
  rec.metadata["source"] = "rosbag " + base_name(path);
  rec.metadata["vehicle"] = map.vehicle;
  rec.metadata["rosbag_topics"] = map.describe();
  rec.metadata["controls"] = from_state ? topics.state + " (chassis state)" : topics.command + " (command)";
  char rate_text[32];
  std::snprintf(rate_text, sizeof rate_text, "%g", rate);
  rec.metadata["rate_hz"] = rate_text;
  return rec;
}

}  // namespace mppi::sysid::bag
