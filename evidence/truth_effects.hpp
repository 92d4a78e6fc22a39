#pragma once
// The hidden effects of the evidence generator, each in its own physical form, with neutral
// defaults (= no effect). Their names, sizes and the effect-table ids a diagnosis may
// reasonably answer with are listed by truth_effect_catalogue().
#include <string>
#include <vector>

namespace mppi::evidence {

struct TruthEffects {
  // Actuators (normalised commands in [-1, 1]).
  double steer_delay_s = 0;       // exact FIFO delay of the steering command
  double throttle_delay_s = 0;    // exact FIFO delay of the throttle command
  double steer_rate_per_s = 0;    // servo rate limit |d steer / dt| (0 = none)
  double steer_backlash = 0;      // play width between servo and wheels (normalised)
  double steer_gain = 1, steer_offset = 0, steer_cubic = 0;  // s -> g s + k s^3 + b
  double throttle_gain = 1;       // ESC gain
  // A stack that commands speeds: the throttle channel asks for the speed top_speed u, and the
  // ESC's PI loop (gains kp [1 per m/s], ki [1 per m]) on the motor's rim speed sets the throttle.
  double speed_loop_top_speed_mps = 0;  // 0 = the channel is a throttle
  double speed_loop_kp = 0.3, speed_loop_ki = 0.6;
  // Battery: terminal voltage = V_oc (1 - capacity_sag q / q_ref) - R I, with R I at stall
  // current = internal_resistance_fraction of V_nominal; q the charge used (stall-current
  // seconds), q_ref = 60 s. The motor torque follows the voltage.
  double battery_internal_resistance_fraction = 0;
  double battery_capacity_sag = 0;
  // Chassis and environment.
  double extra_drag_kgpm = 0;     // -c |v| v along the velocity vector
  // Aerodynamic downforce c v_x^2 [N] pressing both axles (split as the static load): the tyres'
  // force capacity grows with speed. The diagnosis' library has no such term.
  double downforce_kgpm = 0;
  double front_rolling_coefficient = 0, rear_rolling_coefficient = 0;  // per axle, x its load
  double payload_mass_scale = 1, payload_yaw_inertia_scale = 1;
  double weight_shift = 0;        // the CG sits this share of the wheelbase further back (a battery moved)
  double front_torque_share = 0;  // four-wheel drive: an open centre differential sends this share forward
  double grade = 0;               // a hill: constant grade dz/dx of the whole ground plane
  // A bump: a raised-cosine hill of this height [m] (negative: a dip) and radius on the track.
  double bump_height_m = 0;
  double bump_radius_m = 12;
  // Grip patches: `grip_patches` discs of grip `grip_patch_scale` on the track (0 = none).
  int grip_patches = 0;
  double grip_patch_scale = 1;
  // Sensors.
  double gyro_bias_radps = 0;     // the gyro reads r + b
  double speed_sensor_scale = 1;  // the velocity sensor reads s (vx, vy)
  double sensor_time_offset_s = 0;  // states stamped this much against the commands (row at t holds the state of t - offset)
};

// One effect of the catalogue: its key (a TruthEffects field set through set_truth_effect),
// the effect-table ids of dynamics/effects.hpp a diagnosis may name for it ("out of library"
// = none exists: the right answer is naming nothing reliable, or a "suspected" note), and
// whether it is a sensor fault.
struct TruthEffectInfo {
  std::string name;                     // e.g. "steer_delay"
  std::vector<std::string> keys;        // TruthEffects fields it sets
  std::vector<std::string> table_ids;   // acceptable ids; empty = out of library
  std::string form;                     // how it acts here, for the truth file
  std::string small, large;             // sweep sizes "key=value,..." (small = barely visible)
  // In the sweep's grid unless false: the speed loop changes what the drivers' command means (a
  // speed, declared in the recording), so it is run only when asked for (--effects).
  bool in_grid = true;
};
const std::vector<TruthEffectInfo>& truth_effect_catalogue();
const TruthEffectInfo& truth_effect_info(const std::string& name);  // throws mppi::Error

// Sets a field by name ("steer_delay_s=0.08,grade=0.05"); returns the catalogue names of the
// effects touched. Throws mppi::Error for an unknown key or a bad number.
std::vector<std::string> set_truth_effects(const std::string& assignments, TruthEffects* e);

// Field by name (for the truth file).
double truth_effect_value(const TruthEffects& e, const std::string& key);

}  // namespace mppi::evidence
