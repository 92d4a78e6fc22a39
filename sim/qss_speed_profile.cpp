#include "sim/qss_speed_profile.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "base/error.hpp"
#include "dynamics/pacejka.hpp"

namespace mppi::sim {
namespace {

constexpr double kInf = CarLimits::kInf;

void require(bool ok, const std::string& what) {
  if (!ok) throw Error("qss_speed_profile: " + what);
}

void validate(const CarLimits& c) {
  auto finite_positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  auto finite_non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  auto positive_or_inf = [](double v) { return !std::isnan(v) && v > 0.0; };
  require(finite_positive(c.mass_kg), "mass_kg must be finite and > 0, got " + std::to_string(c.mass_kg));
  require(finite_positive(c.gravity_mps2), "gravity_mps2 must be finite and > 0, got " + std::to_string(c.gravity_mps2));
  require(finite_positive(c.mu), "mu must be finite and > 0, got " + std::to_string(c.mu));
  require(finite_non_negative(c.drive_force_N), "drive_force_N must be finite and >= 0");
  require(positive_or_inf(c.no_load_speed_mps), "no_load_speed_mps must be > 0 (or infinite)");
  require(positive_or_inf(c.traction_grip_N), "traction_grip_N must be > 0 (or infinite)");
  require(finite_non_negative(c.brake_force_N), "brake_force_N must be finite and >= 0");
  require(finite_non_negative(c.brake_force_Nspm), "brake_force_Nspm must be finite and >= 0");
  require(positive_or_inf(c.brake_grip_N), "brake_grip_N must be > 0 (or infinite)");
  require(finite_non_negative(c.drag_kgpm), "drag_kgpm must be finite and >= 0");
  require(finite_non_negative(c.rolling_force_N), "rolling_force_N must be finite and >= 0");
  require(finite_non_negative(c.start_speed_mps), "start_speed_mps must be finite and >= 0");
  require(!std::isnan(c.end_speed_mps) && c.end_speed_mps >= 0.0, "end_speed_mps must be >= 0 (or infinite)");
}

// The forces of CarLimits as functions of speed and curvature.
struct Car {
  const CarLimits& c;

  double drive_N(double v) const {
    return std::isinf(c.no_load_speed_mps) ? c.drive_force_N
                                           : c.drive_force_N * std::max(0.0, 1.0 - v / c.no_load_speed_mps);
  }
  double brake_N(double v) const { return c.brake_force_N + c.brake_force_Nspm * v; }
  double resistance_N(double v) const { return c.drag_kgpm * v * v + c.rolling_force_N; }
  // Share of the longitudinal grip that the lateral acceleration v^2 |kappa| leaves.
  double ellipse(double v, double kappa) const {
    const double r = v * v * std::abs(kappa) / (c.mu * c.gravity_mps2);
    return std::sqrt(std::max(0.0, 1.0 - r * r));
  }
  // The longitudinal force that grip (infinite: no limit) leaves at the ellipse share e.
  static double grip_left_N(double grip_N, double e) { return std::isinf(grip_N) ? kInf : grip_N * e; }
  // Net acceleration at speed v with the ellipse taken at v_ellipse (>= v keeps it conservative).
  double accel(double v, double v_ellipse, double kappa) const {
    const double tyre = std::min(drive_N(v), grip_left_N(c.traction_grip_N, ellipse(v_ellipse, kappa)));
    return (tyre - resistance_N(v)) / c.mass_kg;
  }
  double decel(double v, double kappa) const {
    const double tyre = std::min(brake_N(v), grip_left_N(c.brake_grip_N, ellipse(v, kappa)));
    return (tyre + resistance_N(v)) / c.mass_kg;
  }

  // Speed after ds from v accelerating at curvature kappa: midpoint rule in v^2.
  double forward(double v, double kappa, double ds) const {
    const double v_half = std::sqrt(std::max(0.0, v * v + ds * accel(v, v, kappa)));
    return std::sqrt(std::max(0.0, v * v + 2.0 * ds * accel(v_half, std::max(v, v_half), kappa)));
  }
  // The largest speed <= v_now at the station that can brake to v_next over ds, braking at the
  // station's own speed and curvature: v^2 <= v_next^2 + 2 ds decel(v, kappa), by bisection.
  double backward(double v_next, double v_now, double kappa, double ds) const {
    auto excess = [&](double v) { return v * v - v_next * v_next - 2.0 * ds * decel(v, kappa); };
    if (excess(v_now) <= 0.0) return v_now;
    double lo = v_next, hi = v_now;  // excess(lo) <= 0 < excess(hi)
    for (int i = 0; i < 100 && hi - lo > 1e-13 * hi; ++i) {
      const double mid = 0.5 * (lo + hi);
      (excess(mid) <= 0.0 ? lo : hi) = mid;
    }
    return lo;
  }

  // Speed on a straight where the drive no longer beats drag and rolling resistance.
  double top_speed() const {
    auto net = [&](double v) { return std::min(drive_N(v), c.traction_grip_N) - resistance_N(v); };
    if (net(0.0) <= 0.0) return 0.0;
    double hi = c.no_load_speed_mps;
    if (c.drag_kgpm > 0.0) hi = std::min(hi, std::sqrt(std::min(c.drive_force_N, c.traction_grip_N) / c.drag_kgpm) + 1.0);
    if (std::isinf(hi)) return kInf;
    double lo = 0.0;
    for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
      const double mid = 0.5 * (lo + hi);
      (net(mid) > 0.0 ? lo : hi) = mid;
    }
    return lo;
  }
};

}  // namespace

double tyre_peak_friction(const PacejkaParams& tyre, double slip_blend) {
  std::string why;
  if (!tyre.is_valid(&why)) throw Error("tyre_peak_friction: " + why);
  if (!(std::isfinite(slip_blend) && slip_blend > 0.0))
    throw Error("tyre_peak_friction: slip_blend must be finite and > 0");
  const auto coeffs = PacejkaCoeffs<double>::from(tyre);
  double peak = 0.0;
  for (int i = 0; i <= 40000; ++i) {
    const double s = 1e-3 * i;
    peak = std::max(peak, magic_formula_mu(s, coeffs) * std::tanh(s / slip_blend));
  }
  return peak;
}

CarLimits car_limits(const SingleTrackParams& p) {
  std::string why;
  if (!p.is_valid(&why)) throw Error("car_limits: vehicle parameters: " + why);
  const double weight_N = p.mass_kg * p.gravity_mps2;
  const double front_load_N = weight_N * p.cg_to_rear_axle_m / p.wheelbase_m();
  const double rear_load_N = weight_N * p.cg_to_front_axle_m / p.wheelbase_m();
  const double mu_front = tyre_peak_friction(p.tyre, p.slip_blend);
  const double mu_rear = tyre_peak_friction(p.rear_tyre(), p.slip_blend);
  // The motor's force reaches the axles split by front_drive_share; the first axle to slip limits it.
  const double s = p.front_drive_share;
  const double grip_N = std::min(s > 0.0 ? mu_front * front_load_N / s : kInf,
                                 s < 1.0 ? mu_rear * rear_load_N / (1.0 - s) : kInf);
  const double stall_force_N = p.stall_torque_Nm / p.wheel_radius_m;
  CarLimits c;
  c.mass_kg = p.mass_kg;
  c.gravity_mps2 = p.gravity_mps2;
  c.mu = std::min(mu_front, mu_rear);
  c.drive_force_N = stall_force_N;
  c.no_load_speed_mps = p.no_load_speed_mps;
  c.traction_grip_N = grip_N;
  c.brake_force_N = stall_force_N * p.brake_torque_ratio;
  c.brake_force_Nspm = stall_force_N / p.no_load_speed_mps;
  c.brake_grip_N = grip_N;
  c.drag_kgpm = p.aero_drag_kgpm;
  c.rolling_force_N = p.rolling_resistance * weight_N;
  return c;
}

QssProfile qss_speed_profile(const std::vector<double>& ds_m, const std::vector<double>& curvature_1pm,
                             const CarLimits& limits) {
  validate(limits);
  const std::size_t n = curvature_1pm.size();
  require(n >= 2, "needs at least 2 stations (curvature_1pm has " + std::to_string(n) + ")");
  const std::size_t segments = limits.closed ? n : n - 1;
  require(ds_m.size() == segments, "ds_m needs " + std::to_string(segments) + " entries for " + std::to_string(n) +
                                       (limits.closed ? " stations of a closed lap" : " stations of an open path") +
                                       ", got " + std::to_string(ds_m.size()));
  for (std::size_t i = 0; i < segments; ++i)
    require(std::isfinite(ds_m[i]) && ds_m[i] > 0.0, "ds_m[" + std::to_string(i) + "] must be finite and > 0");
  for (std::size_t i = 0; i < n; ++i)
    require(std::isfinite(curvature_1pm[i]), "curvature_1pm[" + std::to_string(i) + "] is not finite");

  const Car car{limits};
  const double v_top = limits.closed ? car.top_speed() : kInf;
  if (limits.closed) require(v_top > 0.0, "the drive cannot overcome the rolling resistance");
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double k = std::abs(curvature_1pm[i]);
    v[i] = std::min(v_top, k > 0.0 ? std::sqrt(limits.mu * limits.gravity_mps2 / k) : kInf);
    require(!limits.closed || std::isfinite(v[i]), "nothing bounds the speed of a closed lap with a straight: give a drag or a no-load speed");
  }
  if (!limits.closed) {
    v[0] = std::min(v[0], limits.start_speed_mps);
    v[n - 1] = std::min(v[n - 1], limits.end_speed_mps);
  }
  // Each pass only lowers speeds; repeat until they hold still (a closed lap wraps around).
  for (int pass = 0; pass < 200; ++pass) {
    double change = 0.0;
    auto lower = [&](std::size_t i, double candidate) {
      if (candidate < v[i]) {
        change = std::max(change, v[i] - candidate);
        v[i] = candidate;
      }
    };
    for (std::size_t i = 0; i < segments; ++i) lower((i + 1) % n, car.forward(v[i], curvature_1pm[i], ds_m[i]));
    for (std::size_t j = segments; j-- > 0;) lower(j, car.backward(v[(j + 1) % n], v[j], curvature_1pm[j], ds_m[j]));
    if (change <= 1e-12 * (1.0 + v[0])) break;
  }

  QssProfile out;
  out.speed_mps = v;
  out.ax_mps2.assign(n, 0.0);
  out.ay_mps2.resize(n);
  for (std::size_t i = 0; i < n; ++i) out.ay_mps2[i] = v[i] * v[i] * curvature_1pm[i];
  for (std::size_t i = 0; i < segments; ++i) {
    const double v_next = v[(i + 1) % n];
    out.ax_mps2[i] = (v_next * v_next - v[i] * v[i]) / (2.0 * ds_m[i]);
    out.time_s += ds_m[i] / (0.5 * (v[i] + v_next));
  }
  return out;
}

}  // namespace mppi::sim
