#include "sysid/vehicle_model_spec.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/single_track.hpp"
#include "sysid/calibration_actuators.hpp"
#include "sysid/model_param_fields.hpp"
#include "sysid/spec_building.hpp"

namespace mppi::sysid {

namespace {

using detail::SingleTrackWithActuators;

// The base parameters (car and actuators) with the estimated ones set to `values`.
struct SingleTrackWith {
  SingleTrackWithActuators base;
  std::vector<std::string> names;
  bool keep_wheelbase = false;
  double wheelbase = 0;

  SingleTrackWithActuators operator()(const std::vector<double>& v) const {
    SingleTrackWithActuators p = base;
    for (std::size_t i = 0; i < names.size(); ++i) *detail::single_track_or_actuator_field(p, names[i]) = v[i];
    if (keep_wheelbase) p.car.cg_to_rear_axle_m = std::max(1e-3, wheelbase - p.car.cg_to_front_axle_m);
    return p;
  }
};

// Explicit Euler in 2-ms substeps; with actuators, the lags and the steering map come first.
decltype(VehicleModelSpec::step) single_track_step(const SingleTrackWith& with, bool actuators) {
  return [with, actuators](const std::vector<double>& v, double* x, const double* u, double dt) {
    const SingleTrackWithActuators p = with(v);
    const SingleTrackCoeffs<double> k = SingleTrackCoeffs<double>::from(p.car);
    detail::substep(dt, 0.002, [&](double h) {
      double steer = u[0], throttle = u[1];
      if (actuators) {
        detail::advance_actuators(p.act, u, h, x + SingleTrack::kNx);
        steer = detail::applied_steer(p.act, x[SingleTrack::kNx]);
        throttle = x[SingleTrack::kNx + 1];
      }
      SingleTrackTerms<double> e;
      single_track_terms(k, x[3], x[4], x[5], x[7], x[8], steer, throttle, &e);
      const double sy = std::sin(x[2]), cy = std::cos(x[2]);
      x[0] += (cy * x[3] - sy * x[4]) * h;
      x[1] += (sy * x[3] + cy * x[4]) * h;
      x[2] += x[5] * h;
      x[3] += e.dvx_mps2 * h;
      x[4] += e.dvy_mps2 * h;
      x[5] += e.dyaw_rate_radps2 * h;
      x[7] += e.domega_front_radps2 * h;
      x[8] += e.domega_rear_radps2 * h;
    });
  };
}

decltype(VehicleModelSpec::init_state) single_track_init_state(double radius, bool actuators) {
  return [radius, actuators](const PreparedRecording& rec, std::size_t row, double* x) {
    const char* cols[6] = {"x", "y", "yaw", "vx", "vy", "yaw_rate"};
    for (int i = 0; i < 6; ++i) x[i] = detail::value_or(rec, cols[i], row, 0.0);
    x[6] = 0;
    const double w = detail::value_or(rec, "wheel_speed", row, x[3]) / radius;
    x[7] = detail::value_or(rec, "omega_front", row, w);
    x[8] = detail::value_or(rec, "omega_rear", row, w);
    if (actuators) {  // steady at the last command until prime() runs the history through them
      x[SingleTrack::kNx] = row > 0 ? rec.steer_over(row - 1) : 0.0;
      x[SingleTrack::kNx + 1] = row > 0 ? rec.throttle_over(row - 1) : 0.0;
    }
  };
}

// The actuator lags run over the commands of the kActuatorPrime_s before `row`.
decltype(VehicleModelSpec::prime) single_track_prime(const SingleTrackWith& with) {
  return [with](const std::vector<double>& v, const PreparedRecording& rec, std::size_t row, double* x) {
    const SingleTrackWithActuators p = with(v);
    const auto& t = rec.t;
    std::size_t first = row;
    while (first > 0 && t[row] - t[first - 1] <= detail::kActuatorPrime_s) --first;
    if (first == row) return;
    x[SingleTrack::kNx] = rec.steer_over(first);
    x[SingleTrack::kNx + 1] = rec.throttle_over(first);
    for (std::size_t i = first; i < row; ++i) {
      const double u[2] = {rec.steer_over(i), rec.throttle_over(i)};
      detail::advance_actuators(p.act, u, t[i + 1] - t[i], x + SingleTrack::kNx);
    }
  };
}

}  // namespace

std::vector<std::string> single_track_param_names() {
  return {"mass_kg", "yaw_inertia_kgm2", "cg_to_front_axle_m", "cg_to_rear_axle_m", "cg_height_m",
          "wheel_radius_m", "front_wheel_inertia_kgm2", "rear_wheel_inertia_kgm2", "max_steer_rad",
          "stall_torque_Nm", "no_load_speed_mps", "brake_torque_ratio", "rolling_resistance", "aero_drag_kgpm",
          "tyre.B", "tyre.C", "tyre.D", "tyre.E", "tyre.Sh", "tyre.Sv", "slip_speed_floor_mps", "slip_blend",
          "rear_tyre_B_scale", "rear_tyre_C_scale", "rear_tyre_D_scale", "steer_lag_s", "throttle_lag_s",
          "steer_cubic", "steer_offset"};
}

VehicleModelSpec single_track_spec(const SingleTrackParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase) {
  std::string why;
  if (!base.is_valid(&why)) throw Error("single-track base parameters: " + why);
  VehicleModelSpec s;
  s.kind = mppi::models::SingleTrackModel::kName;
  s.nx = SingleTrack::kNx;
  s.state_names = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_front", "omega_rear"};
  s.measurable = {{"x", 0}, {"y", 1}, {"yaw", 2}, {"vx", 3}, {"vy", 4}, {"yaw_rate", 5},
                  {"omega_front", 7}, {"omega_rear", 8}};
  const SingleTrackWithActuators base_all{base, {}};
  detail::prepare(s, base_all, estimated, single_track_param_names(), detail::single_track_or_actuator_field);
  const bool actuators = std::any_of(s.estimated.begin(), s.estimated.end(),
                                     [](const std::string& n) { return detail::is_actuator_param(n); });
  if (actuators) {  // the steer and throttle actuator outputs become states
    s.nx = SingleTrack::kNx + 2;
    s.state_names.push_back("steer_applied");
    s.state_names.push_back("throttle_applied");
  }
  const SingleTrackWith with{base_all, s.estimated, keep_wheelbase, base.wheelbase_m()};
  s.step = single_track_step(with, actuators);
  s.init_state = single_track_init_state(base.wheel_radius_m, actuators);
  if (actuators) s.prime = single_track_prime(with);
  s.to_yaml = [with](const std::vector<double>& v) { return to_yaml(with(v).car); };
  s.process_std_per_sqrt_s = {0.01, 0.01, 0.005, 0.2, 0.2, 0.2, 1e-6, 5.0, 5.0};
  if (actuators) s.process_std_per_sqrt_s.insert(s.process_std_per_sqrt_s.end(), {0.01, 0.01});
  return s;
}

}  // namespace mppi::sysid
