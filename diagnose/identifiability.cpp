#include "diagnose/identifiability.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mppi::diagnose {
namespace {

double stddev(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  double s = 0, s2 = 0;
  for (double x : v) {
    s += x;
    s2 += x * x;
  }
  const double n = static_cast<double>(v.size()), mean = s / n;
  return std::sqrt(std::max(0.0, s2 / n - mean * mean));
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// Thresholds below which a channel counts as not excited. Chosen from what a car that only
// drives straight or at constant throttle shows with sensor noise (a few hundredths) and well
// below what any manoeuvre gives (a turn: steer std > 0.1, |ay| > 3 m/s^2). A speed range of 1 m/s
// at 5 m/s already changes a v^2 force by 40 %.
constexpr double kMinSteerStd = 0.05, kMinYawRateStd = 0.05;
constexpr double kMinThrottleStd = 0.05, kMinVxStd = 0.2;
constexpr double kMinLateralAccel = 2.0, kMinSpeedRange = 1.0, kMinLongitudinalAccelStd = 0.8;

std::string format(const char* fmt, double a, double b) {
  char buf[200];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

}  // namespace

ExcitationLevels measure_excitation(const PreparedRecording& d, const std::vector<char>& mask) {
  std::vector<double> steer, r, throttle, vx, ay, ax;
  const int lag = std::max(1, static_cast<int>(std::lround(0.1 / d.dt_s)));
  for (std::size_t k = 0; k < d.rows(); ++k) {
    if (d.piece[k] < 0 || (!mask.empty() && !mask[k])) continue;
    steer.push_back(d.steer[k]);
    r.push_back(d.r[k]);
    throttle.push_back(d.throttle[k]);
    vx.push_back(d.vx[k]);
    ay.push_back(std::abs(d.vx[k] * d.r[k]));
    const std::size_t k1 = k + static_cast<std::size_t>(lag);
    if (d.continuous(k, static_cast<std::size_t>(lag)) && (mask.empty() || mask[k1]))
      ax.push_back((d.vx[k1] - d.vx[k]) / (d.t[k1] - d.t[k]));
  }
  ExcitationLevels x;
  x.steer_std = stddev(steer);
  x.yaw_rate_std = stddev(r);
  x.throttle_std = stddev(throttle);
  x.vx_std_mps = stddev(vx);
  x.speed_range_mps = percentile(vx, 0.95) - percentile(vx, 0.05);
  x.lateral_accel_p95_mps2 = percentile(ay, 0.95);
  x.longitudinal_accel_std_mps2 = stddev(ax);
  x.speed_command = d.speed_command;
  return x;
}

std::string excitation_shortfall(Excitation needs, const ExcitationLevels& x) {
  switch (needs) {
    case Excitation::kAny:
      return "";
    case Excitation::kSteer:
      if (x.steer_std < kMinSteerStd || x.yaw_rate_std < kMinYawRateStd)
        return format("steering not excited (steer std %.3f, yaw-rate std %.3f rad/s)", x.steer_std, x.yaw_rate_std);
      return "";
    case Excitation::kThrottle:
      if (x.throttle_std < kMinThrottleStd || x.vx_std_mps < kMinVxStd)
        return format("throttle not excited (throttle std %.3f, vx std %.2f m/s)", x.throttle_std, x.vx_std_mps);
      return "";
    case Excitation::kCornering:
      if (x.lateral_accel_p95_mps2 < kMinLateralAccel)
        return format("no cornering towards the grip limit (95th percentile |ay| %.2f m/s^2 < %.1f)",
                      x.lateral_accel_p95_mps2, kMinLateralAccel);
      return "";
    case Excitation::kSpeedCommand:
      if (!x.speed_command)
        return "the throttle column is not declared a speed command (metadata line '# throttle_command: speed')";
      return excitation_shortfall(Excitation::kThrottle, x);
    case Excitation::kSpeedRange:
      if (x.speed_range_mps < kMinSpeedRange)
        return format("speed hardly varies (5-95 %% range %.2f m/s < %.1f)", x.speed_range_mps, kMinSpeedRange);
      return "";
    case Excitation::kBraking:
      if (x.longitudinal_accel_std_mps2 < kMinLongitudinalAccelStd)
        return format("little acceleration or braking (std %.2f m/s^2 < %.1f)", x.longitudinal_accel_std_mps2,
                      kMinLongitudinalAccelStd);
      return "";
  }
  return "";
}

int range_limit_param(const EffectSpec& spec, const EffectParams& fitted, double margin) {
  const EffectParams defaults;
  for (std::size_t i = 0; i < spec.params.size(); ++i) {
    if (static_cast<int>(i) < grid_param_count(spec.data_grid)) continue;  // searched over the data, not bounded
    const EffectParamSpec& p = spec.params[i];
    const double v = fitted.*(p.member), d = defaults.*(p.member), tol = margin * (p.hi - p.lo);
    // An end of the search range that is also a closed end of the physical range (a share of 1)
    // bounds the physics, not the search: a value there is an estimate, not a bound.
    const bool lo_closed = p.valid.bounds == Bounds::kClosed || p.valid.bounds == Bounds::kOpenHigh;
    const bool hi_closed = p.valid.bounds == Bounds::kClosed || p.valid.bounds == Bounds::kOpenLow;
    const bool lo_physical = lo_closed && p.valid.lo == p.lo, hi_physical = hi_closed && p.valid.hi == p.hi;
    const bool at_lo = v <= p.lo + tol && std::abs(d - p.lo) > tol && !lo_physical;
    const bool at_hi = v >= p.hi - tol && std::abs(d - p.hi) > tol && !hi_physical;
    if (at_lo || at_hi) return static_cast<int>(i);
  }
  return -1;
}

std::string range_limit_shortfall(const EffectSpec& spec, const EffectParams& fitted, double margin) {
  const int i = range_limit_param(spec, fitted, margin);
  if (i < 0) return "";
  const EffectParamSpec& p = spec.params[static_cast<std::size_t>(i)];
  const double v = fitted.*(p.member);
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s = %.4g sits at the %s end of its search range [%.4g, %.4g]", p.name, v,
                v <= 0.5 * (p.lo + p.hi) ? "lower" : "upper", p.lo, p.hi);
  return buf;
}

}  // namespace mppi::diagnose
