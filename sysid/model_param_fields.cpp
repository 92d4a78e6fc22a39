#include "sysid/model_param_fields.hpp"

#include <map>

namespace mppi::sysid::detail {

double* single_track_field(SingleTrackParams& p, const std::string& n) {
  static const std::map<std::string, double SingleTrackParams::*> m = {
      {"mass_kg", &SingleTrackParams::mass_kg},
      {"yaw_inertia_kgm2", &SingleTrackParams::yaw_inertia_kgm2},
      {"cg_to_front_axle_m", &SingleTrackParams::cg_to_front_axle_m},
      {"cg_to_rear_axle_m", &SingleTrackParams::cg_to_rear_axle_m},
      {"cg_height_m", &SingleTrackParams::cg_height_m},
      {"wheel_radius_m", &SingleTrackParams::wheel_radius_m},
      {"front_wheel_inertia_kgm2", &SingleTrackParams::front_wheel_inertia_kgm2},
      {"rear_wheel_inertia_kgm2", &SingleTrackParams::rear_wheel_inertia_kgm2},
      {"max_steer_rad", &SingleTrackParams::max_steer_rad},
      {"stall_torque_Nm", &SingleTrackParams::stall_torque_Nm},
      {"no_load_speed_mps", &SingleTrackParams::no_load_speed_mps},
      {"brake_torque_ratio", &SingleTrackParams::brake_torque_ratio},
      {"rolling_resistance", &SingleTrackParams::rolling_resistance},
      {"aero_drag_kgpm", &SingleTrackParams::aero_drag_kgpm},
      {"slip_speed_floor_mps", &SingleTrackParams::slip_speed_floor_mps},
      {"slip_blend", &SingleTrackParams::slip_blend},
      {"rear_tyre_B_scale", &SingleTrackParams::rear_tyre_B_scale},
      {"rear_tyre_C_scale", &SingleTrackParams::rear_tyre_C_scale},
      {"rear_tyre_D_scale", &SingleTrackParams::rear_tyre_D_scale}};
  static const std::map<std::string, double PacejkaParams::*> t = {
      {"tyre.B", &PacejkaParams::B}, {"tyre.C", &PacejkaParams::C}, {"tyre.D", &PacejkaParams::D},
      {"tyre.E", &PacejkaParams::E}, {"tyre.Sh", &PacejkaParams::Sh}, {"tyre.Sv", &PacejkaParams::Sv}};
  if (auto it = m.find(n); it != m.end()) return &(p.*(it->second));
  if (auto it = t.find(n); it != t.end()) return &(p.tyre.*(it->second));
  return nullptr;
}

double* full_vehicle_field(FullVehicleParams& p, const std::string& n) {
  static const std::map<std::string, double FullVehicleParams::*> m = {
      {"front_track_m", &FullVehicleParams::front_track_m},
      {"rear_track_m", &FullVehicleParams::rear_track_m},
      {"front_spring_Npm", &FullVehicleParams::front_spring_Npm},
      {"rear_spring_Npm", &FullVehicleParams::rear_spring_Npm},
      {"front_damper_Nspm", &FullVehicleParams::front_damper_Nspm},
      {"rear_damper_Nspm", &FullVehicleParams::rear_damper_Nspm},
      {"sprung_cg_height_m", &FullVehicleParams::sprung_cg_height_m},
      {"roll_centre_height_m", &FullVehicleParams::roll_centre_height_m},
      {"roll_inertia_kgm2", &FullVehicleParams::roll_inertia_kgm2},
      {"pitch_inertia_kgm2", &FullVehicleParams::pitch_inertia_kgm2},
      {"drag_coefficient", &FullVehicleParams::drag_coefficient}};
  if (auto it = m.find(n); it != m.end()) return &(p.*(it->second));
  if (n == "aero_drag_kgpm") return nullptr;  // the full vehicle's drag is drag_coefficient
  return single_track_field(p.base, n);
}

double* double_track_field(DoubleTrackParams& p, const std::string& n) {
  if (n == "front_track_m") return &p.front_track_m;
  if (n == "rear_track_m") return &p.rear_track_m;
  if (n == "front_roll_share") return &p.front_roll_share;
  return single_track_field(p.base, n);
}

double* actuator_field(Actuators& a, const std::string& n) {
  if (n == "steer_lag_s") return &a.steer_lag_s;
  if (n == "throttle_lag_s") return &a.throttle_lag_s;
  if (n == "steer_cubic") return &a.steer_cubic;
  if (n == "steer_offset") return &a.steer_offset;
  return nullptr;
}
bool is_actuator_param(const std::string& n) {
  Actuators a;
  return actuator_field(a, n) != nullptr;
}
double* single_track_or_actuator_field(SingleTrackWithActuators& p, const std::string& n) {
  if (double* f = actuator_field(p.act, n)) return f;
  return single_track_field(p.car, n);
}

bool is_linear_param(const std::string& n) {
  return n == "tyre.E" || n == "tyre.Sh" || n == "tyre.Sv" || is_actuator_param(n);
}

}  // namespace mppi::sysid::detail
