#include "evidence/car_physics.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "base/error.hpp"

namespace mppi::evidence {

CarConstants read_car_constants(const std::string& yaml_path) {
  CarConstants c;
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::Exception& e) {
    throw Error(yaml_path + ": cannot read vehicle constants: " + e.what());
  }
  auto take = [&](const YAML::Node& n, const char* key, double* v) {
    if (!n[key]) return;
    try {
      *v = n[key].as<double>();
    } catch (const YAML::Exception&) {
      throw Error(yaml_path + ": " + key + ": expected a number");
    }
  };
  // Every key this car knows, with where it goes; any other key is an error.
  const std::vector<std::pair<const char*, double*>> top = {
      {"mass_kg", &c.mass_kg},
      {"yaw_inertia_kgm2", &c.yaw_inertia_kgm2},
      {"cg_to_front_axle_m", &c.lf_m},
      {"cg_to_rear_axle_m", &c.lr_m},
      {"cg_height_m", &c.cg_height_m},
      {"wheel_radius_m", &c.wheel_radius_m},
      {"front_wheel_inertia_kgm2", &c.front_wheel_inertia_kgm2},
      {"rear_wheel_inertia_kgm2", &c.rear_wheel_inertia_kgm2},
      {"gravity_mps2", &c.gravity_mps2},
      {"max_steer_rad", &c.max_steer_rad},
      {"stall_torque_Nm", &c.stall_torque_Nm},
      {"no_load_speed_mps", &c.no_load_speed_mps},
      {"brake_torque_ratio", &c.brake_torque_ratio},
      {"rolling_resistance", &c.rolling_coefficient},
      {"rolling_resistance_speed_mps", &c.rolling_speed_mps},
      {"aero_drag_kgpm", &c.aero_drag_kgpm},
      {"slip_speed_floor_mps", &c.slip_floor_mps},
      {"slip_blend", &c.slip_blend},
      {"rear_tyre_B_scale", &c.rear_B_factor},
      {"rear_tyre_C_scale", &c.rear_C_factor},
      {"rear_tyre_D_scale", &c.rear_D_factor},
      {"front_drive_share", &c.front_torque_share},
  };
  const std::vector<std::pair<const char*, double*>> tyre = {
      {"B", &c.mf_B}, {"C", &c.mf_C}, {"D", &c.mf_D}, {"E", &c.mf_E}, {"Sh", &c.mf_Sh}, {"Sv", &c.mf_Sv},
  };
  auto read_all = [&](const YAML::Node& n, const std::vector<std::pair<const char*, double*>>& keys,
                      const std::string& where) {
    if (!n.IsMap()) throw Error(yaml_path + ": " + (where.empty() ? "the file" : where) + ": expected a map of keys");
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      if (where.empty() && key == "tyre") continue;
      if (std::none_of(keys.begin(), keys.end(), [&](const auto& k) { return key == k.first; }))
        throw Error(yaml_path + ": " + where + (where.empty() ? "" : ".") + key +
                    ": unknown vehicle constant (the evidence car does not model it)");
    }
    for (const auto& [key, member] : keys) take(n, key, member);
  };
  read_all(root, top, "");
  if (const YAML::Node t = root["tyre"]) read_all(t, tyre, "tyre");
  return c;
}

double tyre_mu(const CarConstants& c, double total_slip, bool rear) {
  const double B = rear ? c.mf_B * c.rear_B_factor : c.mf_B;
  const double C = rear ? c.mf_C * c.rear_C_factor : c.mf_C;
  const double D = rear ? c.mf_D * c.rear_D_factor : c.mf_D;
  const double shifted = total_slip - c.mf_Sh;
  const double b = B * shifted;
  return D * std::sin(C * std::atan(b - c.mf_E * (b - std::atan(shifted)))) + c.mf_Sv;
}

namespace {

// Friction coefficients (force / load) of one tyre along its own x and y, from the contact
// patch velocity and the rim speed: slips relative to max(|rim speed|, floor), force opposite
// the slip, faded in over the slip blend so that it vanishes at zero slip.
void tyre_coefficients(const CarConstants& c, bool rear, double vx, double vy, double rim_mps, double grip,
                       double* mux, double* muy) {
  const double den = std::max(std::abs(rim_mps), c.slip_floor_mps);
  const double sx = (vx - rim_mps) / den, sy = vy / den;
  const double s = std::hypot(sx, sy);
  if (s < 1e-12) {
    *mux = *muy = 0;
    return;
  }
  const double k = -grip * tyre_mu(c, s, rear) * std::tanh(s / c.slip_blend) / s;
  *mux = k * sx;
  *muy = k * sy;
}

}  // namespace

double motor_wheel_speed(const CarState& s, double front) { return front * s[kWf] + (1 - front) * s[kWr]; }

CarState car_derivative(const CarConstants& c, const CarState& s, const CarInputs& in, CarForces* forces) {
  const double m = c.mass_kg * in.mass_scale, iz = c.yaw_inertia_kgm2 * in.yaw_inertia_scale;
  const double weight = m * c.gravity_mps2;
  const double vx = s[kVx], vy = s[kVy], r = s[kR];
  const double lf_m = c.lf_m + in.cg_rearward_m, lr_m = c.lr_m - in.cg_rearward_m;
  const double d = in.wheel_angle_rad, cd = std::cos(d), sd = std::sin(d);
  // Contact-patch velocities in each tyre's frame.
  const double front_lat_body = vy + lf_m * r;
  const double fvx = cd * vx + sd * front_lat_body, fvy = cd * front_lat_body - sd * vx;
  const double rvx = vx, rvy = vy - lr_m * r;
  double fmx, fmy, rmx, rmy;
  tyre_coefficients(c, false, fvx, fvy, s[kWf] * c.wheel_radius_m, in.grip_scale, &fmx, &fmy);
  tyre_coefficients(c, true, rvx, rvy, s[kWr] * c.wheel_radius_m, in.grip_scale, &rmx, &rmy);
  // Pitch load transfer from the moment balance about the rear contact (explicit in the
  // friction coefficients, which do not depend on the loads).
  const double wheelbase_term = lf_m + lr_m + c.cg_height_m * (fmx * cd - fmy * sd - rmx);
  double fz_front = weight * (lr_m - c.cg_height_m * rmx) / std::max(wheelbase_term, 1e-3);
  fz_front = std::clamp(fz_front, 0.0, weight);
  double fz_rear = weight - fz_front;
  // Downforce acts at the CG's position along the car: the static split.
  const double downforce_N = in.downforce_kgpm * vx * vx;
  fz_front += downforce_N * lr_m / (lf_m + lr_m);
  fz_rear += downforce_N * lf_m / (lf_m + lr_m);
  const double ffx = fmx * fz_front, ffy = fmy * fz_front, frx = rmx * fz_rear, fry = rmy * fz_rear;
  if (forces) *forces = {{ffx, ffy, fz_front}, {frx, fry, fz_rear}};

  // Resistances: the car's own rolling resistance and drag along body x, then the hidden ones.
  double resist_x = -c.rolling_coefficient * weight * std::tanh(vx / c.rolling_speed_mps) -
                    c.aero_drag_kgpm * vx * std::abs(vx);
  double resist_y = 0;
  const double speed = std::hypot(vx, vy);
  resist_x -= in.extra_drag_kgpm * speed * vx;
  resist_y -= in.extra_drag_kgpm * speed * vy;
  // Per-axle rolling resistance along each wheel's rolling direction, x its normal load.
  const double front_roll = -in.front_rolling_coefficient * fz_front * std::tanh(fvx / c.rolling_speed_mps);
  const double rear_roll = -in.rear_rolling_coefficient * fz_rear * std::tanh(rvx / c.rolling_speed_mps);
  resist_x += front_roll * cd + rear_roll;
  resist_y += front_roll * sd;
  const double front_roll_yaw = front_roll * sd * lf_m;

  const double fx_body = ffx * cd - ffy * sd + frx + resist_x;
  const double fy_body = ffx * sd + ffy * cd + fry + resist_y;
  CarState ds{};
  const double cy = std::cos(s[kYaw]), sy = std::sin(s[kYaw]);
  ds[kX] = cy * vx - sy * vy;
  ds[kY] = sy * vx + cy * vy;
  ds[kYaw] = r;
  ds[kVx] = fx_body / m + in.gravity_x_mps2 + vy * r;
  ds[kVy] = fy_body / m + in.gravity_y_mps2 - vx * r;
  ds[kR] = (lf_m * (ffy * cd + ffx * sd) - lr_m * fry + front_roll_yaw) / iz;
  const double front_torque = in.front_torque_share * in.motor_torque_Nm;
  ds[kWf] = (front_torque - ffx * c.wheel_radius_m) / c.front_wheel_inertia_kgm2;
  ds[kWr] = (in.motor_torque_Nm - front_torque - frx * c.wheel_radius_m) / c.rear_wheel_inertia_kgm2;
  return ds;
}

void ground_gravity_body(double slope_x, double slope_y, double yaw_rad, double g_mps2, double* ax_mps2,
                         double* ay_mps2) {
  const double c = std::cos(yaw_rad), sn = std::sin(yaw_rad);
  const double rise_x = slope_x * c + slope_y * sn, rise_y = -slope_x * sn + slope_y * c;
  *ax_mps2 = -g_mps2 * rise_x / std::sqrt(1 + rise_x * rise_x);
  *ay_mps2 = -g_mps2 * rise_y / std::sqrt(1 + rise_y * rise_y);
}

CarState rk4_step(const CarConstants& c, const CarState& s, const CarInputs& in, double dt_s) {
  auto add = [](const CarState& a, const CarState& b, double h) {
    CarState o;
    for (std::size_t i = 0; i < a.size(); ++i) o[i] = a[i] + h * b[i];
    return o;
  };
  const CarState k1 = car_derivative(c, s, in);
  const CarState k2 = car_derivative(c, add(s, k1, dt_s / 2), in);
  const CarState k3 = car_derivative(c, add(s, k2, dt_s / 2), in);
  const CarState k4 = car_derivative(c, add(s, k3, dt_s), in);
  CarState o;
  for (std::size_t i = 0; i < s.size(); ++i) o[i] = s[i] + dt_s / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
  return o;
}

}  // namespace mppi::evidence
