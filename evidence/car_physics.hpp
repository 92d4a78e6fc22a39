#pragma once
// The evidence generator's own car: a single-track vehicle with wheel spin, written here from
// the published equations (AutoRally paper's single-track with Velenis' total-slip Magic
// Formula tyre and pitch load transfer; a DC-motor torque line) and integrated by classical
// Runge-Kutta 4 in double. It shares no code with the models the diagnosis fits: the nominal
// parameters are read from the same vehicle YAML, the equations and the integrator are its own,
// and every hidden effect acts here in its own physical form (truth_effects.hpp).
#include <array>
#include <string>

namespace mppi::evidence {

// Vehicle constants (SI). Defaults: the AutoRally car of data/config/autorally_single_track.yaml.
struct CarConstants {
  double mass_kg = 21.88, yaw_inertia_kgm2 = 1.124;
  double lf_m = 0.34, lr_m = 0.23, cg_height_m = 0.12, wheel_radius_m = 0.0975;
  double front_wheel_inertia_kgm2 = 0.048, rear_wheel_inertia_kgm2 = 0.044, gravity_mps2 = 9.81;
  double mf_B = 1.1559, mf_C = 1.1924, mf_D = 0.9956, mf_E = -0.8505, mf_Sh = -0.0540, mf_Sv = 0.1444;
  double max_steer_rad = 0.38, stall_torque_Nm = 10.0, no_load_speed_mps = 30.0;
  double brake_torque_ratio = 1.0;  // torque at throttle -1 (braking) / stall torque
  double rolling_coefficient = 0.05, rolling_speed_mps = 0.5, aero_drag_kgpm = 0.05;
  double slip_floor_mps = 3.0, slip_blend = 0.1;
  // the rear tyre's B, C and D as multiples of the front's (E, Sh and Sv are shared)
  double rear_B_factor = 1.0, rear_C_factor = 1.0, rear_D_factor = 1.0;
  double front_torque_share = 0.0;  // the motor torque's share on the front axle (0: rear-wheel drive)
};

// Reads a single-track vehicle YAML (yaml-cpp); keys not given keep the defaults. Throws
// mppi::Error naming the file for an unreadable file, a non-numeric value or a key it does not
// know (a constant the nominal model has and this car lacked would make every recording differ
// from the nominal, effect or not).
CarConstants read_car_constants(const std::string& yaml_path);

// x, y, yaw, vx, vy, yaw rate, front and rear wheel speeds [rad/s].
using CarState = std::array<double, 8>;
enum CarIndex { kX, kY, kYaw, kVx, kVy, kR, kWf, kWr };

// What acts on the car during one integration step besides its wheel angle and motor torque.
struct CarInputs {
  double wheel_angle_rad = 0;    // front wheel angle after the steering chain
  double motor_torque_Nm = 0;    // the motor's torque at the wheels (both axles together)
  double front_torque_share = 0; // the part of it that an open centre differential sends to the front axle
  double grip_scale = 1;         // tyre friction x this (the surface under the car)
  double gravity_x_mps2 = 0;     // tangential gravity along body x, y (the grade)
  double gravity_y_mps2 = 0;
  double extra_drag_kgpm = 0;    // aerodynamic drag -c |v| v along the velocity vector
  double downforce_kgpm = 0;     // aerodynamic downforce c v_x^2 on both axles, split as the static load
  double front_rolling_coefficient = 0, rear_rolling_coefficient = 0;  // per axle, x its load
  double mass_scale = 1, yaw_inertia_scale = 1;  // payload
  double cg_rearward_m = 0;      // the CG sits this much nearer the rear axle (l_f + d, l_r - d)
};

// Magic Formula friction coefficient at total slip s (before the grip scale), of the front tyre
// or (rear = true) of the rear one.
double tyre_mu(const CarConstants& c, double total_slip, bool rear = false);

// Tyre forces of one axle in its tyre frame and its normal load, for tests.
struct AxleForces {
  double fx_N = 0, fy_N = 0, fz_N = 0;
};
struct CarForces {
  AxleForces front, rear;
};

// The wheel-equivalent speed [rad/s] of the motor behind an open centre differential that sends
// the share `front` of its torque forward: the axles' speeds weighted by their torque shares.
double motor_wheel_speed(const CarState& s, double front);

// State derivative; `forces` (optional) receives the tyre forces.
CarState car_derivative(const CarConstants& c, const CarState& s, const CarInputs& in, CarForces* forces = nullptr);

// Gravity's component along the ground under each body axis of a car heading yaw_rad on ground
// of slope (dz/dx, dz/dy): -g d / sqrt(1 + d^2) = -g sin(theta), d = the rise per metre along it.
void ground_gravity_body(double slope_x, double slope_y, double yaw_rad, double g_mps2, double* ax_mps2,
                         double* ay_mps2);

// One classical RK4 step of dt_s with the inputs held.
CarState rk4_step(const CarConstants& c, const CarState& s, const CarInputs& in, double dt_s);

}  // namespace mppi::evidence
