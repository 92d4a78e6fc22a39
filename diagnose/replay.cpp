#include "diagnose/replay.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/error.hpp"

namespace mppi::diagnose {

std::vector<Segment> make_segments(const DiagData& d, const std::vector<char>& mask, int len, int stride) {
  std::vector<Segment> out;
  const std::size_t n = d.rows();
  std::size_t k = 0;
  while (k + static_cast<std::size_t>(len) < n) {
    bool ok = d.continuous(k, static_cast<std::size_t>(len));
    for (int i = 0; ok && !mask.empty() && i <= len; ++i) ok = mask[k + static_cast<std::size_t>(i)] != 0;
    if (ok) {
      out.push_back({k, len});
      k += static_cast<std::size_t>(stride);
    } else {
      ++k;
    }
  }
  return out;
}

void predict_segment(const ReplayModel& model, const DiagData& d, const Segment& s,
                     const ReplayOptions& o, double* out) {
  float x[ReplayModel::kMaxStates];
  VehicleState vs;
  const std::size_t k0 = s.start;
  // Sensor faults: the true velocities behind a measurement, and the commands that acted over a
  // state-stamped interval (shifted by the time offset; the interval average of the held commands).
  const SensorFaults& sf = model.sensor;
  const double inv_scale = 1.0 / sf.speed_scale;
  auto true_vx = [&](std::size_t k) { return static_cast<float>(d.vx[k] * inv_scale); };
  auto true_vy = [&](std::size_t k) { return static_cast<float>(d.vy[k] * inv_scale); };
  auto true_r = [&](std::size_t k) { return static_cast<float>(d.r[k] - sf.gyro_bias_radps); };
  // Each command is read this many rows earlier: the states' time offset plus the channel's pure
  // delay. A held command shifted by a fraction of a row averages over two recorded ones.
  const double steer_shift_rows = (sf.time_offset_s + model.command_delay.steer_s) / d.dt_s;
  const double throttle_shift_rows = (sf.time_offset_s + model.command_delay.throttle_s) / d.dt_s;
  auto shifted = [&](std::size_t k, double shift_rows, double (DiagData::*over)(std::size_t) const) {
    if (shift_rows == 0.0) return (d.*over)(k);
    const double pos = static_cast<double>(k) - shift_rows;
    const double lo = std::floor(pos), w = pos - lo;
    const auto at = [&](double i) { return static_cast<std::size_t>(std::clamp(i, 0.0, static_cast<double>(d.rows() - 1))); };
    return (1 - w) * (d.*over)(at(lo)) + w * (d.*over)(at(lo + 1));
  };
  auto command_over = [&](std::size_t k, float* u) {
    u[0] = static_cast<float>(shifted(k, steer_shift_rows, &DiagData::steer_over));
    u[1] = static_cast<float>(shifted(k, throttle_shift_rows, &DiagData::throttle_over));
  };
  vs.x_m = static_cast<float>(d.x[k0]);
  vs.y_m = static_cast<float>(d.y[k0]);
  vs.yaw_rad = static_cast<float>(d.yaw[k0]);
  vs.vx_mps = true_vx(k0);
  vs.vy_mps = true_vy(k0);
  vs.yaw_rate_radps = true_r(k0);
  const bool has_roll = !d.roll.empty() && std::isfinite(d.roll[k0]);
  if (has_roll) vs.roll_rad = static_cast<float>(d.roll[k0]);
  model.init_state(vs, x);
  const int time_state = model.time_index();
  x[time_state] = static_cast<float>(d.t[k0]);
  // Unmeasured states (actuator chains, wheel speeds): run the model over the history before
  // the start with its measured states forced back to the recording at every sample, so that
  // they settle where this model puts them; then start from the measured state.
  std::size_t h = k0;
  const int prime_rows = static_cast<int>(std::lround(o.prime_s / d.dt_s));
  for (int i = 0; i < prime_rows && h > 0 && d.piece[h - 1] == d.piece[k0]; ++i) --h;
  float u[2];
  command_over(h, u);
  model.set_actuators(x, u[0], u[1]);
  // Velocities: a constant-gain observer (blend of the model's value and the measurement) once
  // the full model runs, which takes sensor noise off the start state; the rest measured.
  bool observing = false;
  auto force_measured = [&](std::size_t k) {
    x[state::kX] = static_cast<float>(d.x[k]);
    x[state::kY] = static_cast<float>(d.y[k]);
    x[state::kYaw] = static_cast<float>(d.yaw[k]);
    const float g = observing ? static_cast<float>(o.observer_gain) : 1.f;
    x[state::kVx] += g * (true_vx(k) - x[state::kVx]);
    x[state::kVy] += g * (true_vy(k) - x[state::kVy]);
    x[state::kYawRate] += g * (true_r(k) - x[state::kYawRate]);
    if (has_roll && std::isfinite(d.roll[k])) x[state::kRoll] += g * (static_cast<float>(d.roll[k]) - x[state::kRoll]);
    x[time_state] = static_cast<float>(d.t[k]);
  };
  for (std::size_t k = h; k < k0; ++k) {
    force_measured(k);
    const double dt = d.t[k + 1] - d.t[k];
    const int n = std::max(1, static_cast<int>(std::lround(dt / o.substep_s)));
    command_over(k, u);
    if (static_cast<double>(k0 - k) * d.dt_s > o.wheel_prime_s) {  // actuators only
      model.advance_actuators(x, u[0], u[1], static_cast<float>(dt));
      continue;
    }
    for (int j = 0; j < n; ++j)
      model.step(x, u[0], u[1], static_cast<float>(dt / n));
    observing = true;
  }
  force_measured(k0);
  for (int i = 0; i < s.len; ++i) {
    const std::size_t k = k0 + static_cast<std::size_t>(i);
    const double dt = d.t[k + 1] - d.t[k];
    const int n = std::max(1, static_cast<int>(std::lround(dt / o.substep_s)));
    const float h_s = static_cast<float>(dt / n);
    command_over(k, u);
    for (int j = 0; j < n; ++j)
      model.step(x, u[0], u[1], h_s);
    double* o5 = out + static_cast<std::ptrdiff_t>(i) * kPredStride;
    o5[0] = x[state::kVx] * sf.speed_scale;  // as the sensors would show them
    o5[1] = x[state::kVy] * sf.speed_scale;
    o5[2] = x[state::kYawRate] + sf.gyro_bias_radps;
    o5[3] = x[state::kX];
    o5[4] = x[state::kY];
  }
}

void segment_residuals(const ReplayModel& model, const DiagData& d,
                       const std::vector<Segment>& segs, const std::array<double, kChannels>& scale,
                       const ReplayOptions& o, std::vector<double>* res) {
  std::size_t total = 0;
  for (const auto& s : segs) total += static_cast<std::size_t>(s.len) * kChannels;
  res->resize(total);
  std::vector<double> pred;
  std::size_t w = 0;
  for (const auto& s : segs) {
    pred.resize(static_cast<std::size_t>(s.len) * kPredStride);
    predict_segment(model, d, s, o, pred.data());
    for (int i = 0; i < s.len; ++i) {
      const std::size_t k = s.start + static_cast<std::size_t>(i) + 1;
      for (int c = 0; c < kChannels; ++c) {
        double e = (pred[static_cast<std::size_t>(i) * kPredStride + c] - d.channel(c, k)) / scale[c];
        if (!std::isfinite(e)) e = 1e3;  // a model that blew up: large, finite
        (*res)[w++] = std::clamp(e, -1e3, 1e3);
      }
    }
  }
}

std::array<double, kChannels> channel_scales(const DiagData& d, const std::vector<char>& mask) {
  const double floor[kChannels] = {0.05, 0.02, 0.02};
  std::array<double, kChannels> out{};
  for (int c = 0; c < kChannels; ++c) {
    double s = 0, s2 = 0;
    std::size_t n = 0;
    for (std::size_t k = 0; k < d.rows(); ++k) {
      if ((!mask.empty() && !mask[k]) || d.piece[k] < 0) continue;
      const double v = d.channel(c, k);
      s += v;
      s2 += v * v;
      ++n;
    }
    const double mean = n ? s / n : 0;
    out[c] = std::max(floor[c], n ? std::sqrt(std::max(0.0, s2 / n - mean * mean)) : 0.0);
  }
  return out;
}

std::vector<HorizonMetrics> horizon_metrics(const ReplayModel& model, const DiagData& d,
                                            const std::vector<char>& mask,
                                            const std::vector<double>& horizons_s, int stride,
                                            const ReplayOptions& o, const DiagData* reference) {
  if (reference && reference->rows() != d.rows())
    throw Error("horizon_metrics: the reference states have " + std::to_string(reference->rows()) +
                " rows, the recording " + std::to_string(d.rows()));
  const DiagData& ref = reference ? *reference : d;
  std::vector<HorizonMetrics> out;
  const auto scale = channel_scales(d, mask);
  for (double hs : horizons_s) {
    HorizonMetrics m;
    m.horizon_s = hs;
    const int len = std::max(1, static_cast<int>(std::lround(hs / d.dt_s)));
    const auto segs = make_segments(d, mask, len, stride);
    m.starts = static_cast<int>(segs.size());
    if (segs.empty()) {
      out.push_back(m);
      continue;
    }
    std::vector<double> pred(static_cast<std::size_t>(len) * kPredStride);
    std::array<double, kChannels> se{}, sy{}, sy2{};
    double pos = 0;
    for (const auto& s : segs) {
      predict_segment(model, d, s, o, pred.data());
      const std::size_t k = s.start + static_cast<std::size_t>(len);
      const double* p = pred.data() + static_cast<std::size_t>(len - 1) * kPredStride;
      for (int c = 0; c < kChannels; ++c) {
        const double y = ref.channel(c, k);
        const double e = std::isfinite(p[c]) ? p[c] - y : 1e3;
        se[c] += e * e;
        sy[c] += y;
        sy2[c] += y * y;
      }
      const double ex = p[3] - ref.x[k], ey = p[4] - ref.y[k];
      pos += std::isfinite(ex + ey) ? ex * ex + ey * ey : 1e6;
    }
    const double n = static_cast<double>(segs.size());
    double nr = 0;
    for (int c = 0; c < kChannels; ++c) {
      m.rmse[c] = std::sqrt(se[c] / n);
      const double var = std::max(1e-12, sy2[c] / n - (sy[c] / n) * (sy[c] / n));
      m.fit_percent[c] = 100.0 * (1.0 - std::sqrt(se[c] / n) / std::sqrt(var));
      nr += (m.rmse[c] / scale[c]) * (m.rmse[c] / scale[c]);
    }
    m.normalized_rmse = std::sqrt(nr / kChannels);
    m.position_rmse_m = std::sqrt(pos / n);
    out.push_back(m);
  }
  return out;
}

}  // namespace mppi::diagnose
