#include "sysid/vehicle_model_spec.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "dynamics/double_track.hpp"
#include "dynamics/full_vehicle.hpp"
#include "dynamics/model_registry.hpp"
#include "sysid/model_param_fields.hpp"
#include "sysid/spec_building.hpp"

namespace mppi::sysid {

std::vector<std::string> full_vehicle_param_names() {
  auto v = single_track_param_names();
  v.erase(std::find(v.begin(), v.end(), "aero_drag_kgpm"));
  v.erase(std::remove_if(v.begin(), v.end(), detail::is_actuator_param), v.end());  // single-track only
  for (const char* n : {"front_track_m", "rear_track_m", "front_spring_Npm", "rear_spring_Npm",
                        "front_damper_Nspm", "rear_damper_Nspm", "sprung_cg_height_m",
                        "roll_centre_height_m", "roll_inertia_kgm2", "pitch_inertia_kgm2", "drag_coefficient"})
    v.push_back(n);
  return v;
}

std::vector<std::string> double_track_param_names() {
  auto v = single_track_param_names();
  v.erase(std::remove_if(v.begin(), v.end(), detail::is_actuator_param), v.end());  // single-track only
  for (const char* n : {"front_track_m", "rear_track_m", "front_roll_share"}) v.push_back(n);
  return v;
}

VehicleModelSpec double_track_spec(const DoubleTrackParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase) {
  std::string why;
  if (!base.is_valid(&why)) throw Error("double-track base parameters: " + why);
  VehicleModelSpec s;
  s.kind = mppi::models::DoubleTrackModel::kName;
  s.nx = DoubleTrack::kNx;
  s.state_names = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf", "omega_rf", "omega_lr", "omega_rr"};
  s.measurable = {{"x", 0}, {"y", 1}, {"yaw", 2}, {"vx", 3}, {"vy", 4}, {"yaw_rate", 5},
                  {"omega_lf", 7}, {"omega_rf", 8}, {"omega_lr", 9}, {"omega_rr", 10}};
  detail::prepare(s, base, estimated, double_track_param_names(), detail::double_track_field);
  const double wheelbase = base.base.wheelbase_m();
  const std::vector<std::string> names = s.estimated;
  auto with = [base, names, keep_wheelbase, wheelbase](const std::vector<double>& v) {
    DoubleTrackParams p = base;
    for (std::size_t i = 0; i < names.size(); ++i) *detail::double_track_field(p, names[i]) = v[i];
    if (keep_wheelbase) p.base.cg_to_rear_axle_m = std::max(1e-3, wheelbase - p.base.cg_to_front_axle_m);
    return p;
  };
  s.step = [with](const std::vector<double>& v, double* x, const double* u, double dt) {
    const FourWheelCoeffs<double> k = double_track_coeffs(with(v));
    detail::substep(dt, 0.002, [&](double h) {  // explicit Euler, as DoubleTrack::step
      double dx[DoubleTrack::kNx];
      DoubleTrack::derivatives(k, x, u, dx);
      for (int i = 0; i < DoubleTrack::kNx; ++i) x[i] += dx[i] * h;
    });
  };
  const double radius = base.base.wheel_radius_m;
  s.init_state = [radius](const PreparedRecording& rec, std::size_t row, double* x) {
    const char* cols[11] = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf", "omega_rf",
                            "omega_lr", "omega_rr"};
    for (int i = 0; i < 6; ++i) x[i] = detail::value_or(rec, cols[i], row, 0.0);
    x[6] = 0;
    const double w = detail::value_or(rec, "wheel_speed", row, x[3]) / radius;
    for (int i = 7; i <= 10; ++i) x[i] = detail::value_or(rec, cols[i], row, w);
  };
  s.to_yaml = [with](const std::vector<double>& v) { return to_yaml(with(v)); };
  s.process_std_per_sqrt_s = {0.01, 0.01, 0.005, 0.2, 0.2, 0.2, 1e-6, 5, 5, 5, 5};
  return s;
}

VehicleModelSpec full_vehicle_spec(const FullVehicleParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase) {
  std::string why;
  if (!base.is_valid(&why)) throw Error("full-vehicle base parameters: " + why);
  VehicleModelSpec s;
  s.kind = mppi::models::FullVehicleModel::kName;
  s.nx = FullVehicle::kNx;
  s.state_names = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf", "omega_rf", "omega_lr",
                   "omega_rr", "pitch", "heave", "roll_rate", "pitch_rate", "vz"};
  s.measurable = {{"x", 0}, {"y", 1}, {"yaw", 2}, {"vx", 3}, {"vy", 4}, {"yaw_rate", 5}, {"roll", 6},
                  {"omega_lf", 7}, {"omega_rf", 8}, {"omega_lr", 9}, {"omega_rr", 10}, {"pitch", 11},
                  {"roll_rate", 13}, {"pitch_rate", 14}, {"vz", 15}};
  detail::prepare(s, base, estimated, full_vehicle_param_names(), detail::full_vehicle_field);
  const double wheelbase = base.base.wheelbase_m();
  const std::vector<std::string> names = s.estimated;
  auto with = [base, names, keep_wheelbase, wheelbase](const std::vector<double>& v) {
    FullVehicleParams p = base;
    for (std::size_t i = 0; i < names.size(); ++i) *detail::full_vehicle_field(p, names[i]) = v[i];
    if (keep_wheelbase) p.base.cg_to_rear_axle_m = std::max(1e-3, wheelbase - p.base.cg_to_front_axle_m);
    return p;
  };
  s.step = [with](const std::vector<double>& v, double* x, const double* u, double dt) {
    const FullVehicleCoeffs<double> k = full_vehicle_coeffs(with(v));
    detail::substep(dt, 0.002, [&](double h) { FullVehicle::step_double(k, x, u, h); });
  };
  const double radius = base.base.wheel_radius_m;
  s.init_state = [radius](const PreparedRecording& rec, std::size_t row, double* x) {
    const char* cols[16] = {"x", "y", "yaw", "vx", "vy", "yaw_rate", "roll", "omega_lf", "omega_rf",
                            "omega_lr", "omega_rr", "pitch", "heave", "roll_rate", "pitch_rate", "vz"};
    for (int i = 0; i < 16; ++i) x[i] = detail::value_or(rec, cols[i], row, 0.0);
    const double w = detail::value_or(rec, "wheel_speed", row, x[3]) / radius;
    for (int i = 7; i <= 10; ++i)
      if (!rec.has_column(cols[i]) || !std::isfinite(rec.column(cols[i])[row])) x[i] = w;
  };
  s.to_yaml = [with](const std::vector<double>& v) { return to_yaml(with(v)); };
  s.process_std_per_sqrt_s = {0.01, 0.01, 0.005, 0.2, 0.2, 0.2, 0.005, 5, 5, 5, 5, 0.005, 0.001, 0.1, 0.1, 0.05};
  return s;
}

}  // namespace mppi::sysid
