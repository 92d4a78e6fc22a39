#pragma once
// The effects of the sim-vs-real tool as one table: each effect is a named physical term with
// its parameters (member of EffectParams, unit, the range a model accepts, the range a fit
// searches, a typical size) and the place where it enters the physics (its hook in
// WithEffects<Model>, dynamics/with_effects.hpp). The corrected-model file reader and writer,
// EffectParams::is_valid, the candidate library of `mppi-fit diagnose` and the docs' list all
// come from this table.
//
// Effects (their ids in reports and files) and hooks:
//   actuator: steer_offset, steer_gain    delta = (gain * s_applied + offset) * max_steer
//             throttle_offset             throttle u_applied + b (a motor dead band when b < 0)
//             steer_delay, throttle_delay pure delays, rolled out as a chain of
//                                         kActuatorDelayStages first-order stages of
//                                         delay/kActuatorDelayStages each (an Erlang
//                                         approximation any integrator can step)
//             steer_lag, throttle_lag     first-order actuators, time constant tau
//             motor_voltage_sag           throttle u -> u - k max(u, 0)^2 (battery sag)
//             throttle_gain               throttle u -> g u (motor / ESC gain)
//             steer_cubic                 steer s -> s + k s^3 (nonlinear steering linkage)
//             steer_asymmetry             steer s -> (1 + a) s left, (1 - a) s right
//             steer_rate_limit,           the applied command needs at least T seconds per
//             throttle_rate_limit         unit of change (servo speed, ESC ramp): |du/dt| <= 1/T
//             steer_backlash              play of width b between servo and wheels
//             speed_loop                  the throttle channel carries a speed command: the car's
//                                         low-level loop asks for the speed V u and sets the
//                                         throttle V u / v_nl + k e + k_i int e dt, e = V u - v
//                                         (feedforward from the motor's no-load speed v_nl, PI on
//                                         the driven wheels' rim speed v; the integral held while
//                                         the throttle is at +-1), clamped to [-1, 1]. Only for
//                                         recordings that declare a speed command
//   chassis:  tire_saturation             Magic Formula peak D -> k D, B -> s B / k
//             friction_change             grip (D, Sv) x g from time t_change on
//             grip_patch                  grip x g on one to three discs of the ground (centre,
//                                         radius each; one surface, so one g; a smooth edge a
//                                         quarter of a metre wide). The second and third discs
//                                         are optional: radius 0 = no disc
//             load_transfer               CG height h -> h + dh (pitch load transfer)
//             weight_distribution         the CG sits s of the wheelbase L further back: l_f + s L,
//                                         l_r - s L (the axles' static loads; s < 0: forward)
//             drive_split                 a share d of the motor's torque moves to the front
//                                         axle (front_drive_share + d, kept in [0, 1]): a
//                                         four-wheel-drive car modelled as rear-wheel drive
//                                         (single-track core only)
//             payload                     mass x m, yaw inertia x j
//             motor_speed                 no-load speed x v (the motor's torque-speed line)
//             motor_freewheel             share f of the drive's back-EMF braking that acts only
//                                         while the PWM is on: the drive force becomes
//                                         F_stall (u - v / v_nl ((1 - f) + f |u|)); f = 1 is the
//                                         (a - b v) u motor law of RC-car models (an ESC that
//                                         lets the motor freewheel in the off-time). Needs the
//                                         single-track core's motor; applied as the command
//                                         that gives this torque through the base's motor law
//                                         (so the tyres still limit it)
//             drag_brake                  the ESC's drag brake: with the command in its neutral
//                                         band the ESC brakes the driven wheels with the torque
//                                         that decelerates the car by a_db (m R a_db). Applied as
//                                         the command that adds this torque through the base's
//                                         motor law (so the tyres still limit it), from the driven
//                                         wheels' speed; single-track-core models only. With
//                                         motor_freewheel (f = 1: no back-EMF braking at neutral)
//                                         it is the neutral of a PWM ESC in drive-brake mode
//             tyre_relaxation             the lateral force lags the slip over a rolling distance
//                                         (declared in dynamics/effects/tyre_relaxation.hpp)
//   sensor:   gyro_bias                   the yaw-rate gyro reads r + b
//             speed_sensor_scale          the velocity sensor reads s (vx, vy)
//             time_offset                 states are stamped t_off late against the commands.
//                                         A late stamp looks exactly like equal delays of both
//                                         actuators, so the diagnosis searches only early stamps
//                                         (t_off < 0: responses before their commands, which no
//                                         physics can produce). Sensor effects change what
//                                         a recording shows, not the car: the diagnosis' replay
//                                         applies them, WithEffects' physics ignores them.
//   force:    aero_drag                   extra force -c vx |vx|
//             rolling_resistance          extra force -(F0 tanh(v / 0.5) + b v) at each axle along its
//                                         wheel (v: its rolling speed), shared as the static load
//             road_grade                  a tilted plane z = gx x + gy y: -m g grad z
//             ground_bump                 a hill (h > 0) or dip (h < 0) at a place: z = h (1 + cos(pi d /
//                                         R)) / 2 within R of its centre, 0 beyond: -m g grad z
// Every effect is off at its default value.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "base/param_table.hpp"
#include "dynamics/effect_spec.hpp"
#include "dynamics/effects/effect_registry.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi {

// The built-in effects' parameters, and through its base those of the effects declared in files
// of their own (dynamics/effects/effect_registry.hpp).
struct EffectParams : effects::ParamsOfAll<effects::DeclaredEffects> {
  double steer_offset = 0.0;         // [-] added to the applied steer
  double steer_gain = 1.0;           // [-] scale of the applied steer
  double throttle_offset = 0.0;      // [-] added to the applied throttle
  double steer_delay_s = 0.0;        // [s] pure delay
  double throttle_delay_s = 0.0;     // [s] pure delay
  double steer_lag_s = 0.0;          // [s] first-order time constant
  double throttle_lag_s = 0.0;       // [s] first-order time constant
  double aero_drag_kgpm = 0.0;       // [N s^2/m^2] c in -c vx |vx|
  double rolling_force_N = 0.0;      // [N] Coulomb force F0
  double rolling_viscous_Nspm = 0.0; // [N s/m] viscous b
  double tyre_peak_scale = 1.0;      // [-] k in D -> k D, B -> s B / k
  double tyre_stiffness_scale = 1.0; // [-] s, cornering stiffness factor
  double grip_scale = 1.0;           // [-] grip factor g after the change
  double grip_change_time_s = 0.0;   // [s] time of the grip change (time is a state)
  double cg_height_delta_m = 0.0;    // [m] dh added to the CG height
  double cg_shift_rear = 0.0;        // [-] s: the CG moves s x wheelbase towards the rear axle
  double front_drive_shift = 0.0;    // [-] d: share of the motor torque moved to the front axle
  double voltage_sag = 0.0;          // [-] k in u - k max(u,0)^2
  double grade_x = 0.0;              // [-] slope dz/dx of the ground plane
  double grade_y = 0.0;              // [-] slope dz/dy of the ground plane
  double throttle_gain = 1.0;        // [-] g in u -> g u
  double steer_cubic = 0.0;          // [-] k in s -> s + k s^3
  double steer_asymmetry = 0.0;      // [-] a: left (s > 0) x (1 + a), right x (1 - a)
  double steer_slew_s = 0.0;         // [s] time per unit of applied steer: |ds/dt| <= 1/T (0 = none)
  double throttle_slew_s = 0.0;      // [s] time per unit of applied throttle (0 = none)
  double steer_backlash = 0.0;       // [-] width of the play (normalised steer)
  double mass_scale = 1.0;           // [-] payload: mass x m
  double yaw_inertia_scale = 1.0;    // [-] payload: yaw inertia x j
  double motor_speed_scale = 1.0;    // [-] no-load speed x v
  double motor_freewheel_share = 0.0; // [-] f: share of the back-EMF braking scaled by |u|
  double drag_brake_mps2 = 0.0;      // [m/s^2] the ESC's drag brake at neutral command
  double gyro_bias_radps = 0.0;      // [rad/s] measured yaw rate = r + b
  double speed_scale = 1.0;          // [-] measured vx, vy = s x true
  double time_offset_s = 0.0;        // [s] states stamped late against the commands
  double patch_x_m = 0.0;            // [m] centre of the grip patch (world frame)
  double patch_y_m = 0.0;            // [m]
  double patch_radius_m = 0.0;       // [m] radius of the grip patch
  double patch_grip_scale = 1.0;     // [-] grip factor on the patch (1 = no patch)
  double patch2_x_m = 0.0;           // [m] centre of a second disc of the same surface
  double patch2_y_m = 0.0;           // [m]
  double patch2_radius_m = 0.0;      // [m] its radius (0 = no second disc)
  double patch3_x_m = 0.0;           // [m] centre of a third disc of the same surface
  double patch3_y_m = 0.0;           // [m]
  double patch3_radius_m = 0.0;      // [m] its radius (0 = no third disc)
  double bump_x_m = 0.0;             // [m] centre of the ground bump (world frame)
  double bump_y_m = 0.0;             // [m]
  double bump_radius_m = 0.0;        // [m] its radius (where the ground is level again)
  double bump_height_m = 0.0;        // [m] its height at the centre (negative: a dip; 0 = none)
  double speed_loop_top_speed_mps = 0.0;  // [m/s] V: the command u asks for the speed V u (0 = no loop)
  double speed_loop_gain = 0.5;      // [1 per m/s] k: throttle per m/s of speed error
  double speed_loop_integral_gain = 0.0;  // [1 per m] k_i: throttle per m of integrated speed error

  bool is_valid(std::string* why) const;
};

// An effect declared in a file of its own as an EffectSpec of the table.
template <class E>
EffectSpec effect_spec_of() {
  const EffectDecl<typename E::Params> d = E::decl();  // the same fields over E's own parameters
  EffectSpec spec{d.id, d.description, d.hook, {}, d.grid, d.data_grid, d.needs, d.dynamics_of, d.partner,
                  d.default_candidate};
  for (const auto& p : d.params)
    spec.params.push_back({p.name, static_cast<double EffectParams::*>(p.member), p.unit, p.valid, p.lo, p.hi, p.scale});
  return spec;
}
// The built-in effects followed by the declared ones (dynamics/effects/effect_registry.hpp).
inline std::vector<EffectSpec> with_declared_effects(std::vector<EffectSpec> table) {
  for_each_type(effects::DeclaredEffects{}, [&]<class E>() { table.push_back(effect_spec_of<E>()); });
  return table;
}

// Every effect, in a fixed order.
inline const std::vector<EffectSpec>& effect_table() {
  using E = EffectParams;
  using H = EffectHook;
  using X = Excitation;
  static const Range kAny = any_finite(), kNonNeg = non_negative(), kScale = {0.05, kInf, Bounds::kOpen},
                     kGrade = open(-0.5, 0.5);
  static const std::vector<EffectSpec> table = with_declared_effects({
      {"aero_drag", "extra air drag F = -c vx|vx|", H::kForce,
       {{"aero_drag_kgpm", &E::aero_drag_kgpm, "N s^2/m^2", kAny, -0.05, 3.0, 0.1}}, {}, DataGrid::kNone, X::kSpeedRange},
      {"rolling_resistance", "extra rolling resistance F = -(F0 tanh(v/0.5) + b v) along each wheel, shared by the axles as the static load", H::kForce,
       {{"rolling_force_N", &E::rolling_force_N, "N", kAny, -10.0, 60.0, 2.0},
        {"rolling_viscous_Nspm", &E::rolling_viscous_Nspm, "N s/m", kAny, -5.0, 30.0, 1.0}}, {}, DataGrid::kNone, X::kSpeedRange},
      {"steer_delay", "pure delay of the steering command", H::kActuator,
       {{"steer_delay_s", &E::steer_delay_s, "s", kNonNeg, 0.0, 0.4, 0.05}}, {0.03, 0.06, 0.1, 0.15, 0.25}, DataGrid::kNone, X::kSteer, "steer"},
      {"throttle_delay", "pure delay of the throttle command", H::kActuator,
       {{"throttle_delay_s", &E::throttle_delay_s, "s", kNonNeg, 0.0, 0.4, 0.05}}, {0.03, 0.06, 0.1, 0.15, 0.25},
       DataGrid::kNone, X::kThrottle, "throttle"},
      {"steer_lag", "first-order steering actuator", H::kActuator,
       {{"steer_lag_s", &E::steer_lag_s, "s", kNonNeg, 0.0, 0.6, 0.05}}, {0.03, 0.06, 0.1, 0.15, 0.25}, DataGrid::kNone, X::kSteer, "steer"},
      {"throttle_lag", "first-order throttle / motor response", H::kActuator,
       {{"throttle_lag_s", &E::throttle_lag_s, "s", kNonNeg, 0.0, 1.0, 0.05}}, {0.03, 0.06, 0.1, 0.2, 0.4}, DataGrid::kNone, X::kThrottle, "throttle"},
      {"steer_offset", "steering bias (trim)", H::kActuator,
       {{"steer_offset", &E::steer_offset, "1 (normalised steer)", kAny, -0.4, 0.4, 0.02}}, {}, DataGrid::kNone, X::kSteer},
      {"steer_gain", "steering scale (servo / linkage gain)", H::kActuator,
       {{"steer_gain", &E::steer_gain, "1", kAny, 0.3, 2.0, 0.1}}, {0.7, 1.0, 1.3}, DataGrid::kNone, X::kSteer, {},
       "steer_offset"},
      {"throttle_offset", "throttle bias / motor dead band", H::kActuator,
       {{"throttle_offset", &E::throttle_offset, "1 (normalised throttle)", kAny, -0.4, 0.4, 0.02}}, {}, DataGrid::kNone, X::kThrottle},
      {"tire_saturation", "tyre friction limit (Pacejka peak D x k) and cornering stiffness (x s)", H::kChassis,
       {{"tyre_peak_scale", &E::tyre_peak_scale, "1", kScale, 0.3, 3.0, 0.1},
        {"tyre_stiffness_scale", &E::tyre_stiffness_scale, "1", kScale, 0.2, 5.0, 0.1}}, {0.6, 1.0, 1.4}, DataGrid::kNone, X::kCornering},
      {"friction_change", "grip (whole friction curve) x g from time t_change on", H::kChassis,
       {{"grip_change_time_s", &E::grip_change_time_s, "s", kAny, 0.0, 1e9, 1.0},
        {"grip_scale", &E::grip_scale, "1", kScale, 0.3, 3.0, 0.1}}, {}, DataGrid::kTime, X::kCornering},
      {"grip_patch", "grip (whole friction curve) x g on one to three discs of the ground: patches of other surface", H::kChassis,
       {{"patch_x_m", &E::patch_x_m, "m", kAny, -1e9, 1e9, 1.0},
        {"patch_y_m", &E::patch_y_m, "m", kAny, -1e9, 1e9, 1.0},
        {"patch_radius_m", &E::patch_radius_m, "m", kNonNeg, 0.0, 30.0, 0.5},
        {"patch_grip_scale", &E::patch_grip_scale, "1", kScale, 0.3, 3.0, 0.1},
        {"patch2_x_m", &E::patch2_x_m, "m", kAny, -1e9, 1e9, 1.0},
        {"patch2_y_m", &E::patch2_y_m, "m", kAny, -1e9, 1e9, 1.0},
        {"patch2_radius_m", &E::patch2_radius_m, "m", kNonNeg, 0.0, 30.0, 0.5},
        {"patch3_x_m", &E::patch3_x_m, "m", kAny, -1e9, 1e9, 1.0},
        {"patch3_y_m", &E::patch3_y_m, "m", kAny, -1e9, 1e9, 1.0},
        {"patch3_radius_m", &E::patch3_radius_m, "m", kNonNeg, 0.0, 30.0, 0.5}},
       {}, DataGrid::kPlace, X::kCornering},
      {"ground_bump", "a hill or dip on the ground: z = h (1 + cos(pi d / R)) / 2 within R of a place", H::kForce,
       {{"bump_x_m", &E::bump_x_m, "m", kAny, -1e9, 1e9, 1.0},
        {"bump_y_m", &E::bump_y_m, "m", kAny, -1e9, 1e9, 1.0},
        {"bump_radius_m", &E::bump_radius_m, "m", kNonNeg, 0.0, 40.0, 0.5},
        {"bump_height_m", &E::bump_height_m, "m", kAny, -2.0, 2.0, 0.05}}, {}, DataGrid::kPlace, X::kAny},
      {"load_transfer", "pitch load transfer: CG height h + dh", H::kChassis,
       {{"cg_height_delta_m", &E::cg_height_delta_m, "m", kAny, -0.115, 0.12, 0.02}}, {}, DataGrid::kNone, X::kBraking},
      {"weight_distribution", "the CG sits elsewhere along the wheelbase: l_f + s L, l_r - s L (s > 0: rearward)", H::kChassis,
       {{"cg_shift_rear", &E::cg_shift_rear, "1 (of the wheelbase)", open(-1.0, 1.0), -0.4, 0.4, 0.02}}, {-0.1, 0.1},
       DataGrid::kNone, X::kAny},
      {"drive_split", "a share d of the drive and brake torque acts on the front axle (four-wheel drive)", H::kChassis,
       {{"front_drive_shift", &E::front_drive_shift, "1 (of the motor torque)", closed(-1.0, 1.0), 0.0, 1.0, 0.05}},
       {0.3, 0.6}, DataGrid::kNone, X::kThrottle},
      {"motor_voltage_sag", "drive falls with current: throttle u - k max(u,0)^2", H::kActuator,
       {{"voltage_sag", &E::voltage_sag, "1", {0.0, 1.0, Bounds::kOpenHigh}, 0.0, 0.9, 0.05}}, {}, DataGrid::kNone, X::kThrottle},
      {"road_grade", "tilted ground plane z = gx x + gy y", H::kForce,
       {{"grade_x", &E::grade_x, "1 (dz/dx)", kGrade, -0.3, 0.3, 0.01},
        {"grade_y", &E::grade_y, "1 (dz/dy)", kGrade, -0.3, 0.3, 0.01}}, {}, DataGrid::kNone, X::kAny},
      {"throttle_gain", "motor / ESC gain: throttle u -> g u", H::kActuator,
       {{"throttle_gain", &E::throttle_gain, "1", kScale, 0.3, 2.5, 0.1}}, {0.7, 1.0, 1.4}, DataGrid::kNone, X::kThrottle,
       {}, "throttle_offset"},
      // k is searched down to -0.9: a fit of a soft linkage (k = -0.4) that also takes up other
      // large-steer errors can end below -0.6, and a fit at the range's end is only a bound.
      {"steer_cubic", "nonlinear steering linkage: s -> s + k s^3", H::kActuator,
       {{"steer_cubic", &E::steer_cubic, "1", open(-1.0, 2.0), -0.9, 1.0, 0.1}}, {-0.3, 0.3}, DataGrid::kNone, X::kSteer},
      {"steer_asymmetry", "left and right steering gains differ: x (1 + a) left, x (1 - a) right", H::kActuator,
       {{"steer_asymmetry", &E::steer_asymmetry, "1", open(-0.9, 0.9), -0.4, 0.4, 0.05}}, {}, DataGrid::kNone, X::kSteer},
      {"steer_rate_limit", "steering servo speed: the applied steer needs T seconds per unit of change", H::kActuator,
       {{"steer_slew_s", &E::steer_slew_s, "s (per unit of normalised steer)", kNonNeg, 0.0, 3.0, 0.05}},
       {0.1, 0.3, 0.8}, DataGrid::kNone, X::kSteer, "steer"},
      {"throttle_rate_limit", "throttle ramp: the applied throttle needs T seconds per unit of change", H::kActuator,
       {{"throttle_slew_s", &E::throttle_slew_s, "s (per unit of normalised throttle)", kNonNeg, 0.0, 3.0, 0.05}},
       {0.1, 0.3, 0.8}, DataGrid::kNone, X::kThrottle, "throttle"},
      {"steer_backlash", "play of width b between the steering servo and the wheels", H::kActuator,
       {{"steer_backlash", &E::steer_backlash, "1 (normalised steer)", closed(0.0, 0.5), 0.0, 0.3, 0.02}},
       {0.02, 0.05, 0.1}, DataGrid::kNone, X::kSteer, "steer"},
      {"payload", "mass and yaw inertia differ from the nominal (payload, battery)", H::kChassis,
       {{"mass_scale", &E::mass_scale, "1", kScale, 0.5, 2.5, 0.1},
        {"yaw_inertia_scale", &E::yaw_inertia_scale, "1", kScale, 0.5, 2.5, 0.1}}, {0.8, 1.2, 1.5}, DataGrid::kNone, X::kThrottle},
      {"motor_speed", "the drivetrain's torque-speed line: no-load speed x v", H::kChassis,
       {{"motor_speed_scale", &E::motor_speed_scale, "1", kScale, 0.3, 3.0, 0.1}}, {0.6, 1.0, 1.5}, DataGrid::kNone, X::kSpeedRange},
      {"motor_freewheel", "the motor's back-EMF braking acts only while the PWM is on: F_stall (u - v/v_nl ((1-f) + f|u|))",
       H::kChassis,
       {{"freewheel_share", &E::motor_freewheel_share, "1", closed(0.0, 1.0), 0.0, 1.0, 0.1}}, {0.3, 0.7},
       DataGrid::kNone, X::kThrottle, {}, "drag_brake"},
      {"drag_brake", "the ESC's drag brake: at neutral command a brake torque that decelerates the car by a_db",
       H::kChassis,
       {{"drag_brake_mps2", &E::drag_brake_mps2, "m/s^2", kNonNeg, 0.0, 8.0, 0.5}}, {1.0, 3.0},
       DataGrid::kNone, X::kThrottle},
      {"gyro_bias", "sensor fault: the yaw-rate gyro reads r + b", H::kSensor,
       {{"gyro_bias_radps", &E::gyro_bias_radps, "rad/s", kAny, -0.5, 0.5, 0.01}}, {}, DataGrid::kNone, X::kSteer},
      {"speed_sensor_scale", "sensor fault: the velocity sensor reads s x (vx, vy)", H::kSensor,
       {{"speed_scale", &E::speed_scale, "1", kScale, 0.5, 1.5, 0.02}}, {}, DataGrid::kNone, X::kAny},
      {"time_offset", "sensor fault: states stamped t late against the commands (negative: early)", H::kSensor,
       {{"time_offset_s", &E::time_offset_s, "s", open(-0.5, 0.5), -0.3, 0.0, 0.01}}, {-0.1, -0.04}, DataGrid::kNone, X::kSteer},
      {"speed_loop", "the throttle channel is a speed command: a PI loop sets the throttle V u / v_nl + k e + k_i int e, e = V u - v",
       H::kActuator,
       {{"speed_loop_top_speed_mps", &E::speed_loop_top_speed_mps, "m/s (at full command)", kNonNeg, 0.0, 40.0, 1.0},
        {"speed_loop_gain", &E::speed_loop_gain, "1 per m/s", positive(), 0.02, 5.0, 0.1},
        {"speed_loop_integral_gain", &E::speed_loop_integral_gain, "1 per m", kNonNeg, 0.0, 20.0, 0.2}},
       {4.0, 8.0, 15.0}, DataGrid::kNone, X::kSpeedCommand},
  });
  return table;
}

// The spec of an id; throws mppi::Error listing the ids if unknown.
inline const EffectSpec& effect_spec(const std::string& id) {
  std::string ids;
  for (const auto& e : effect_table()) {
    if (e.id == id) return e;
    ids += (ids.empty() ? "" : ", ") + e.id;
  }
  throw Error("unknown effect '" + id + "' (valid: " + ids + ")");
}

// The grip patch's optional discs (the second and third: centre x, y and radius each; radius 0 =
// no disc). Their parameters take part in a fit only while the disc is there.
struct OptionalDisc {
  double EffectParams::*x;
  double EffectParams::*y;
  double EffectParams::*radius;
};
inline constexpr OptionalDisc kOptionalPatchDiscs[] = {
    {&EffectParams::patch2_x_m, &EffectParams::patch2_y_m, &EffectParams::patch2_radius_m},
    {&EffectParams::patch3_x_m, &EffectParams::patch3_y_m, &EffectParams::patch3_radius_m},
};
// The optional disc a parameter belongs to, or nullptr for every other parameter.
inline const OptionalDisc* optional_disc_of(const EffectParamSpec& p) {
  for (const OptionalDisc& d : kOptionalPatchDiscs)
    if (p.member == d.x || p.member == d.y || p.member == d.radius) return &d;
  return nullptr;
}
inline bool is_optional_disc_param(const EffectParamSpec& p) { return optional_disc_of(p) != nullptr; }
// False for a parameter of an optional disc that `e` does not have; true for every other one.
inline bool effect_param_active(const EffectParamSpec& p, const EffectParams& e) {
  const OptionalDisc* d = optional_disc_of(p);
  return !d || e.*(d->radius) > 0.0;
}

// The effect parameters as a parameter table (keys as in the corrected-model file).
inline std::vector<ParamField> param_table(EffectParams& e) {
  std::vector<ParamField> fields;
  for (const EffectSpec& spec : effect_table())
    for (const EffectParamSpec& p : spec.params)
      fields.push_back(param(p.name, &(e.*(p.member)), p.unit, p.valid, spec.description.c_str()));
  return fields;
}

inline bool EffectParams::is_valid(std::string* why) const {
  EffectParams copy = *this;
  std::string error = first_range_error(param_table(copy));
  if (error.empty() && bump_height_m != 0.0 && !(bump_radius_m > 0.0))
    error = "bump_height_m = " + std::to_string(bump_height_m) + " needs bump_radius_m > 0 (the bump's extent)";
  if (!error.empty() && why) *why = error;
  return error.empty();
}

// The nominal single-track parameters with the chassis effects applied. `grip` scales the
// friction curve (D and Sv).
inline SingleTrackParams apply_effect_params(SingleTrackParams p, const EffectParams& e, double grip) {
  p.tyre.D *= e.tyre_peak_scale * grip;
  p.tyre.Sv *= grip;
  p.tyre.B *= e.tyre_stiffness_scale / e.tyre_peak_scale;
  p.cg_height_m += e.cg_height_delta_m;
  const double wheelbase_m = p.cg_to_front_axle_m + p.cg_to_rear_axle_m;
  p.cg_to_front_axle_m += e.cg_shift_rear * wheelbase_m;
  p.cg_to_rear_axle_m -= e.cg_shift_rear * wheelbase_m;
  p.front_drive_share = std::min(std::max(p.front_drive_share + e.front_drive_shift, 0.0), 1.0);
  p.mass_kg *= e.mass_scale;
  p.yaw_inertia_kgm2 *= e.yaw_inertia_scale;
  p.no_load_speed_mps *= e.motor_speed_scale;
  return p;
}

// One actuator channel per step: blend factors 1 - exp(-dt / tau) of its stages (1 for tau = 0;
// a delay is rolled out as kActuatorDelayStages first-order stages of delay /
// kActuatorDelayStages each), the largest change of the applied command in one step (rate limit
// x dt; +inf = none) and the width of its play (backlash; 0 = none).
inline constexpr int kActuatorDelayStages = 4;
struct ChainCoeffs {
  float a_delay, a_lag, max_step, backlash;
};
struct ActuatorCoeffs {
  ChainCoeffs steer, throttle;
};
inline constexpr float kInfF = std::numeric_limits<float>::infinity();

// The neutral band of an ESC (normalised command): the drag brake acts fully within
// kEscNeutralFull of 0 and fades out linearly to kEscNeutralEdge (hobby ESCs: about 5-10 %).
inline constexpr float kEscNeutralFull = 0.05f, kEscNeutralEdge = 0.10f;
inline ActuatorCoeffs actuator_coeffs(const EffectParams& e, float dt_s) noexcept {
  auto a = [dt_s](double tau) { return tau > 0 ? static_cast<float>(1.0 - std::exp(-dt_s / tau)) : 1.f; };
  const auto step = [dt_s](double slew_s) { return slew_s > 0 ? static_cast<float>(dt_s / slew_s) : kInfF; };
  return {{a(e.steer_delay_s / kActuatorDelayStages), a(e.steer_lag_s), step(e.steer_slew_s),
           static_cast<float>(e.steer_backlash)},
          {a(e.throttle_delay_s / kActuatorDelayStages), a(e.throttle_lag_s), step(e.throttle_slew_s), 0.f}};
}

}  // namespace mppi
