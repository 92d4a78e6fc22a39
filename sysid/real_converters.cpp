#include "sysid/real_data.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "base/error.hpp"
#include "sysid/pose_signals.hpp"
#include "sysid/raw_csv.hpp"

namespace mppi::sysid {

namespace {

using detail::need;
using detail::RawTable;
using detail::smooth_derivative;
using detail::unwrap;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

sim::Recording make_recording(const std::vector<std::string>& extra_names) {
  sim::Recording rec;
  rec.columns.assign(sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end());
  rec.columns.insert(rec.columns.end(), extra_names.begin(), extra_names.end());
  rec.data.resize(rec.columns.size());
  return rec;
}

std::vector<double>& col(sim::Recording& rec, const std::string& name) {
  for (std::size_t i = 0; i < rec.columns.size(); ++i)
    if (rec.columns[i] == name) return rec.data[i];
  throw Error("internal: no column " + name);
}

// The rows to keep: those whose time increases strictly (a missing time is an error).
std::vector<std::size_t> increasing_time_rows(const RawTable& raw, int c_time, const std::string& source) {
  std::vector<std::size_t> keep;
  double last = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < raw.rows(); ++i) {
    const double ti = raw.cols[c_time][i];
    if (!std::isfinite(ti)) {
      throw Error(source + ":" + std::to_string(raw.line_of_row[i]) + ": column " +
                  std::to_string(c_time + 1) + " (" + raw.names[c_time] + "): time is missing");
    }
    if (ti > last) {
      keep.push_back(i);
      last = ti;
    }
  }
  if (keep.size() < 2) throw Error(source + ": fewer than 2 rows with increasing time");
  return keep;
}

// The DART car's CoM pose and body velocities from the Vicon columns (NaN without Vicon).
struct DartMotion {
  std::vector<double> t, x, y, yaw, vx, vy, yaw_rate;
};

DartMotion dart_motion(const RawTable& raw, const std::string& source, const RealConvertSettings& s, bool vicon,
                       int c_time, const std::vector<std::size_t>& keep) {
  const double t0 = raw.cols[c_time][keep.front()];
  std::vector<double> t, x, y, yaw_w;
  for (std::size_t i : keep) {
    t.push_back(raw.cols[c_time][i] - t0);
    if (vicon) {
      x.push_back(raw.cols[need(raw, "vicon x", source)][i]);
      y.push_back(raw.cols[need(raw, "vicon y", source)][i]);
      yaw_w.push_back(raw.cols[need(raw, "vicon yaw", source)][i]);
    }
  }
  const std::size_t n = keep.size();
  std::vector<double> yaw(n, kNaN), vx(n, kNaN), vy(n, kNaN), r(n, kNaN);
  std::vector<double> px(n, kNaN), py(n, kNaN);
  if (vicon) {
    yaw = unwrap(yaw_w);
    for (std::size_t k = 0; k < n; ++k) {
      px[k] = x[k] - s.cog_offset_m * std::cos(yaw[k]);
      py[k] = y[k] - s.cog_offset_m * std::sin(yaw[k]);
    }
    const auto dx = smooth_derivative(t, px, s.smoothing_half_window);
    const auto dy = smooth_derivative(t, py, s.smoothing_half_window);
    r = smooth_derivative(t, yaw, s.smoothing_half_window);
    for (std::size_t k = 0; k < n; ++k) {
      const double c = std::cos(yaw[k]), sn = std::sin(yaw[k]);
      vx[k] = c * dx[k] + sn * dy[k];
      vy[k] = -sn * dx[k] + c * dy[k];
    }
  }
  return {std::move(t), std::move(px), std::move(py), std::move(yaw), std::move(vx), std::move(vy), std::move(r)};
}

sim::Recording convert_dart(const RawTable& raw, const std::string& source, const RealConvertSettings& s) {
  const bool vicon = raw.index("vicon time") >= 0;
  const int c_sens_t = need(raw, "elapsed time sensors", source);
  const int c_ax = need(raw, "acc x (IMU)", source), c_ay = need(raw, "acc y (IMU)", source);
  const int c_w = need(raw, "W (IMU)", source), c_enc = need(raw, "vel encoder", source);
  const int c_safe = need(raw, "safety_value", source);
  const int c_thr = need(raw, "throttle", source), c_steer = need(raw, "steering", source);
  const int c_time = vicon ? need(raw, "vicon time", source) : c_sens_t;
  sim::Recording rec = make_recording({"ax", "ay", "wheel_speed", "imu_yaw_rate", "safety"});
  rec.metadata["vehicle"] = "dart_jetracer";
  rec.metadata["source"] = source;
  rec.metadata["converter"] = "mppi-fit convert (sysid/real_data.cpp)";
  rec.metadata["mass_kg"] = "1.58";
  rec.metadata["wheelbase_m"] = "0.1735";
  rec.metadata["cg_to_rear_axle_m"] = "0.093";
  const std::vector<std::size_t> keep = increasing_time_rows(raw, c_time, source);
  const DartMotion m = dart_motion(raw, source, s, vicon, c_time, keep);
  for (std::size_t k = 0; k < keep.size(); ++k) {
    const std::size_t i = keep[k];
    const bool sensors = raw.cols[c_sens_t][i] != 0.0;  // 0 before the first sensor packet
    auto sensor = [&](int c) { return sensors ? raw.cols[c][i] : kNaN; };
    const double safety = raw.cols[c_safe][i];
    col(rec, "t").push_back(m.t[k]);
    col(rec, "x").push_back(m.x[k]);
    col(rec, "y").push_back(m.y[k]);
    col(rec, "yaw").push_back(m.yaw[k]);
    col(rec, "vx").push_back(vicon ? m.vx[k] : sensor(c_enc));
    col(rec, "vy").push_back(m.vy[k]);
    col(rec, "yaw_rate").push_back(vicon ? m.yaw_rate[k] : sensor(c_w));
    col(rec, "steer").push_back(std::clamp(raw.cols[c_steer][i], -1.0, 1.0));
    col(rec, "throttle").push_back(safety == 0.0 ? 0.0 : std::clamp(raw.cols[c_thr][i], -1.0, 1.0));
    col(rec, "ax").push_back(sensor(c_ax));
    col(rec, "ay").push_back(sensor(c_ay));
    col(rec, "wheel_speed").push_back(sensor(c_enc));
    col(rec, "imu_yaw_rate").push_back(sensor(c_w));
    col(rec, "safety").push_back(safety);
  }
  if (!vicon) rec.metadata["note"] = "no Vicon in this file: x, y, yaw, vy missing; vx = encoder, yaw_rate = IMU";
  return rec;
}

sim::Recording convert_eth(const RawTable& raw, const std::string& source, const RealConvertSettings& s) {
  const int c_t = need(raw, "t_nominal_s", source), c_x = need(raw, "x_m", source);
  const int c_y = need(raw, "y_m", source), c_th = need(raw, "theta_rad", source);
  const int c_vx = need(raw, "vx_world_mps", source), c_vy = need(raw, "vy_world_mps", source);
  const int c_om = need(raw, "omega_radps", source);
  const int c_st = need(raw, "steer_cmd", source), c_thr = need(raw, "throttle_cmd", source);
  sim::Recording rec = make_recording({"step"});
  rec.metadata["vehicle"] = "eth_lasgroup_rccar";
  rec.metadata["source"] = source;
  rec.metadata["converter"] = "mppi-fit convert (sysid/real_data.cpp)";
  rec.metadata["note"] = "time is nominal (1/30 s steps): the source stored no timestamps";
  const auto yaw = unwrap(raw.cols[c_th]);
  double last = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < raw.rows(); ++i) {
    const double t = raw.cols[c_t][i];
    if (!(t > last))
      throw Error(source + ":" + std::to_string(raw.line_of_row[i]) + ": column " +
                  std::to_string(c_t + 1) + " (t_nominal_s): time does not increase");
    last = t;
    const double c = std::cos(yaw[i]), sn = std::sin(yaw[i]);
    const double vxw = raw.cols[c_vx][i], vyw = raw.cols[c_vy][i];
    const double om = raw.cols[c_om][i];
    col(rec, "t").push_back(t);
    col(rec, "x").push_back(raw.cols[c_x][i]);
    col(rec, "y").push_back(raw.cols[c_y][i]);
    col(rec, "yaw").push_back(yaw[i]);
    col(rec, "vx").push_back(c * vxw + sn * vyw);
    col(rec, "vy").push_back(-sn * vxw + c * vyw);
    col(rec, "yaw_rate").push_back(std::abs(om) > s.eth_omega_outlier_radps ? kNaN : om);
    col(rec, "steer").push_back(std::clamp(raw.cols[c_st][i], -1.0, 1.0));
    col(rec, "throttle").push_back(std::clamp(raw.cols[c_thr][i], -1.0, 1.0));
    const int c_step = raw.index("step");
    col(rec, "step").push_back(c_step >= 0 ? raw.cols[c_step][i] : kNaN);
  }
  return rec;
}

}  // namespace

bool RealConvertSettings::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (smoothing_half_window < 1 || smoothing_half_window > 200)
    return fail("smoothing_half_window must be in [1, 200]");
  if (!std::isfinite(cog_offset_m) || std::abs(cog_offset_m) > 1) return fail("cog_offset_m must be in [-1, 1]");
  if (!(eth_omega_outlier_radps > 0)) return fail("eth_omega_outlier_radps must be > 0");
  return true;
}

sim::Recording convert_real_recording(const std::string& text, const std::string& source_name,
                                      const RealConvertSettings& settings) {
  std::string why;
  if (!settings.is_valid(&why)) throw Error("RealConvertSettings: " + why);
  const RawTable raw = detail::parse_raw_csv(text, source_name);
  RealSource src = settings.source;
  if (src == RealSource::kAuto) {
    if (raw.index("elapsed time sensors") >= 0)
      src = RealSource::kDartJetracer;
    else if (raw.index("t_nominal_s") >= 0)
      src = RealSource::kEthRccar;
    else
      throw Error(source_name + ":1: header is neither the DART JetRacer layout ('elapsed time "
                  "sensors', ...) nor the ETH RC-car layout ('t_nominal_s', ...)");
  }
  return src == RealSource::kDartJetracer ? convert_dart(raw, source_name, settings)
                                          : convert_eth(raw, source_name, settings);
}

}  // namespace mppi::sysid
