#pragma once
// The quasi-steady-state (QSS) speed profile of a car along a path given by its curvature:
// the fastest speed at each station that the tyres' friction ellipse, the drivetrain's
// torque-speed line and the brake line allow, by the standard three passes
//   1. lateral cap      v <= sqrt(mu g / |kappa|)    (and the top speed on a straight),
//   2. forward pass     v dv/ds = a_x(v)             (drive, within the ellipse, less drag),
//   3. backward pass    v dv/ds = -a_brake(v)        (brake, within the ellipse, plus drag),
// a closed lap repeating the passes until the speed where it starts is consistent.
// The friction ellipse on the driven (braked) axles' tyre force F_x at lateral acceleration a_y:
//   (F_x / grip)^2 + (a_y / (mu g))^2 <= 1.
// Used by sim/limit_lap.hpp on a racing line; exposed so that its closed forms can be tested
// without a track.
#include <limits>
#include <vector>

#include "dynamics/vehicle_params.hpp"

namespace mppi::sim {

// What limits a car's speed along a path. Forces are the tyres' at the road [N].
struct CarLimits {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double mass_kg = 0.0;
  double gravity_mps2 = 9.81;
  double mu = 0.0;                       // lateral friction: |a_y| <= mu g [-]
  // Drive line at full throttle: F = drive_force_N (1 - v / no_load_speed_mps), and at most
  // traction_grip_N (the driven axles' tyres at a_y = 0), shrunk by the ellipse.
  double drive_force_N = 0.0;            // at v = 0 [N]
  double no_load_speed_mps = kInf;       // speed where the drive line reaches 0 [m/s]
  double traction_grip_N = kInf;         // [N]
  // Brake line at full brake: F = brake_force_N + brake_force_Nspm * v, at most brake_grip_N
  // (the braked axles' tyres at a_y = 0), shrunk by the ellipse.
  double brake_force_N = 0.0;            // at v = 0 [N]
  double brake_force_Nspm = 0.0;         // growth with speed [N s/m]
  double brake_grip_N = kInf;            // [N]
  double drag_kgpm = 0.0;                // c_d: drag force c_d v^2 [N s^2/m^2]
  double rolling_force_N = 0.0;          // rolling resistance, constant while moving [N]
  // A closed lap (the last station joins the first) or an open path from start_speed_mps to
  // end_speed_mps (infinite = free).
  bool closed = true;
  double start_speed_mps = 0.0;          // open path: speed at the first station
  double end_speed_mps = kInf;           // open path: at most this at the last station
};

// The limits of the single-track model's car (dynamics/single_track.hpp) at static loads:
//   mu      = min of the front and rear tyre's peak friction, the largest mu(s) tanh(s / slip_blend)
//             of the Magic Formula (D + Sv for C >= 1; rear: D x rear_tyre_D_scale);
//   loads   f_Fz = m g l_r / L, f_Rz = m g l_f / L (the model's, without load transfer);
//   drive   the rear-axle torque line T = stall_torque (u - omega R / no_load_speed) at u = 1:
//           F = (stall_torque / R)(1 - v / no_load_speed); the grip of the driven axles, the
//           motor's torque split by front_drive_share s: min(mu_F f_Fz / s, mu_R f_Rz / (1 - s));
//   brake   the line at u = -1: F = (stall_torque / R)(brake_torque_ratio + v / no_load_speed),
//           through the same axles;
//   drag    aero_drag_kgpm v^2, rolling resistance rolling_resistance m g.
// Throws mppi::Error naming the field for parameters that fail SingleTrackParams::is_valid.
CarLimits car_limits(const SingleTrackParams& p);

// The largest friction coefficient of a tyre: max over slips s in [0, 40] of
// mu(s) tanh(s / slip_blend), the model's force per normal load (dynamics/pacejka.hpp).
double tyre_peak_friction(const PacejkaParams& tyre, double slip_blend);

// Speed along the path and the accelerations that go with it.
struct QssProfile {
  std::vector<double> speed_mps;  // at each station
  // Longitudinal acceleration from station i to the next, (v_{i+1}^2 - v_i^2) / (2 ds_i); the
  // last station of an open path has 0. Net of drag and rolling resistance.
  std::vector<double> ax_mps2;
  std::vector<double> ay_mps2;    // lateral acceleration v_i^2 kappa_i (signed as kappa)
  double time_s = 0.0;            // sum of ds_i / ((v_i + v_{i+1}) / 2)
};

// The QSS profile. curvature_1pm: one value per station (left turns positive). ds_m: the
// distance from station i to i + 1, one per station on a closed lap (the last one back to the
// first), one less on an open path. The forward pass takes the acceleration at station i's
// curvature over its segment (midpoint rule in v^2), the backward pass the braking at station
// i's speed and curvature (implicit, by bisection), so every (a_x, a_y) pair of the profile
// lies in the friction ellipse at its station.
// Throws mppi::Error naming the input for: empty or mismatched vectors, a non-finite or
// non-positive ds, non-finite curvature, non-positive mass, mu or g, negative or NaN forces,
// or a closed lap whose speed nothing bounds (no drag, no no-load speed, a straight).
QssProfile qss_speed_profile(const std::vector<double>& ds_m, const std::vector<double>& curvature_1pm,
                             const CarLimits& limits);

}  // namespace mppi::sim
