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
//   tyre:     tire_saturation             Magic Formula peak D -> k D, B -> s B / k
//             friction_change             grip (D, Sv) x g from time t_change on
//             load_transfer               CG height h -> h + dh (pitch load transfer)
//   force:    aero_drag                   extra force -c vx |vx|
//             rolling_resistance          extra force -(F0 tanh(vx / 0.5) + b vx)
//             road_grade                  a tilted plane z = gx x + gy y: -m g grad z
// Every effect is off at its default value.
#include <cmath>
#include <string>
#include <vector>

#include "dynamics/vehicle_params.hpp"
#include "mppi/error.hpp"
#include "mppi/param_table.hpp"

namespace mppi {

struct EffectParams {
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
  double voltage_sag = 0.0;          // [-] k in u - k max(u,0)^2
  double grade_x = 0.0;              // [-] slope dz/dx of the ground plane
  double grade_y = 0.0;              // [-] slope dz/dy of the ground plane

  bool is_valid(std::string* why) const;
};

// Where an effect enters the physics of WithEffects<Model>.
enum class EffectHook {
  kActuator,  // transforms the command before the model sees it
  kTyre,      // changes the model's tyre / chassis parameters (models with a single-track core)
  kForce,     // adds a force along the body axes (inside the force balance where the model
              // offers it, else after the model's step)
};

struct EffectParamSpec {
  const char* name;             // key in the corrected-model file (EffectParams field)
  double EffectParams::*member;
  const char* unit;
  Range valid;                  // values a model accepts (is_valid)
  double lo, hi;                // range a fit searches (fits are projected onto it)
  double scale;                 // typical size: finite-difference step = 0.01 scale
};

struct EffectSpec {
  std::string id;               // effect id, e.g. "steer_delay"
  std::string description;      // one line, physical meaning
  EffectHook hook;
  std::vector<EffectParamSpec> params;
  std::vector<double> grid;     // start values searched for params[0] (empty: its default)
  bool time_grid = false;       // params[0] is a time searched over the data (not LM-fitted)
};

// Every effect, in a fixed order.
inline const std::vector<EffectSpec>& effect_table() {
  using E = EffectParams;
  using H = EffectHook;
  static const Range kAny = any_finite(), kNonNeg = non_negative(), kScale = {0.05, kInf, Bounds::kOpen},
                     kGrade = open(-0.5, 0.5);
  static const std::vector<EffectSpec> table = {
      {"aero_drag", "extra air drag F = -c vx|vx|", H::kForce,
       {{"aero_drag_kgpm", &E::aero_drag_kgpm, "N s^2/m^2", kAny, -0.05, 3.0, 0.1}}, {}, false},
      {"rolling_resistance", "extra rolling resistance F = -(F0 tanh(vx/0.5) + b vx)", H::kForce,
       {{"rolling_force_N", &E::rolling_force_N, "N", kAny, -10.0, 60.0, 2.0},
        {"rolling_viscous_Nspm", &E::rolling_viscous_Nspm, "N s/m", kAny, -5.0, 30.0, 1.0}}, {}, false},
      {"steer_delay", "pure delay of the steering command", H::kActuator,
       {{"steer_delay_s", &E::steer_delay_s, "s", kNonNeg, 0.0, 0.4, 0.05}}, {0.03, 0.06, 0.1, 0.15, 0.25}, false},
      {"throttle_delay", "pure delay of the throttle command", H::kActuator,
       {{"throttle_delay_s", &E::throttle_delay_s, "s", kNonNeg, 0.0, 0.4, 0.05}}, {0.03, 0.06, 0.1, 0.15, 0.25},
       false},
      {"steer_lag", "first-order steering actuator", H::kActuator,
       {{"steer_lag_s", &E::steer_lag_s, "s", kNonNeg, 0.0, 0.6, 0.05}}, {0.03, 0.06, 0.1, 0.15, 0.25}, false},
      {"throttle_lag", "first-order throttle / motor response", H::kActuator,
       {{"throttle_lag_s", &E::throttle_lag_s, "s", kNonNeg, 0.0, 1.0, 0.05}}, {0.03, 0.06, 0.1, 0.2, 0.4}, false},
      {"steer_offset", "steering bias (trim)", H::kActuator,
       {{"steer_offset", &E::steer_offset, "1 (normalised steer)", kAny, -0.4, 0.4, 0.02}}, {}, false},
      {"steer_gain", "steering scale (servo / linkage gain)", H::kActuator,
       {{"steer_gain", &E::steer_gain, "1", kAny, 0.3, 2.0, 0.1}}, {0.7, 1.0, 1.3}, false},
      {"throttle_offset", "throttle bias / motor dead band", H::kActuator,
       {{"throttle_offset", &E::throttle_offset, "1 (normalised throttle)", kAny, -0.4, 0.4, 0.02}}, {}, false},
      {"tire_saturation", "tyre friction limit (Pacejka peak D x k) and cornering stiffness (x s)", H::kTyre,
       {{"tyre_peak_scale", &E::tyre_peak_scale, "1", kScale, 0.3, 3.0, 0.1},
        {"tyre_stiffness_scale", &E::tyre_stiffness_scale, "1", kScale, 0.2, 5.0, 0.1}}, {0.6, 1.0, 1.4}, false},
      {"friction_change", "grip (whole friction curve) x g from time t_change on", H::kTyre,
       {{"grip_change_time_s", &E::grip_change_time_s, "s", kAny, 0.0, 1e9, 1.0},
        {"grip_scale", &E::grip_scale, "1", kScale, 0.3, 3.0, 0.1}}, {}, true},
      {"load_transfer", "pitch load transfer: CG height h + dh", H::kTyre,
       {{"cg_height_delta_m", &E::cg_height_delta_m, "m", kAny, -0.115, 0.12, 0.02}}, {}, false},
      {"motor_voltage_sag", "drive falls with current: throttle u - k max(u,0)^2", H::kActuator,
       {{"voltage_sag", &E::voltage_sag, "1", {0.0, 1.0, Bounds::kOpenHigh}, 0.0, 0.9, 0.05}}, {}, false},
      {"road_grade", "tilted ground plane z = gx x + gy y", H::kForce,
       {{"grade_x", &E::grade_x, "1 (dz/dx)", kGrade, -0.3, 0.3, 0.01},
        {"grade_y", &E::grade_y, "1 (dz/dy)", kGrade, -0.3, 0.3, 0.01}}, {}, false},
  };
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
  const std::string error = first_range_error(param_table(copy));
  if (!error.empty() && why) *why = error;
  return error.empty();
}

// The nominal single-track parameters with the tyre effects applied. `grip` scales the
// friction curve (D and Sv).
inline SingleTrackParams apply_effect_params(SingleTrackParams p, const EffectParams& e, double grip) {
  p.tyre.D *= e.tyre_peak_scale * grip;
  p.tyre.Sv *= grip;
  p.tyre.B *= e.tyre_stiffness_scale / e.tyre_peak_scale;
  p.cg_height_m += e.cg_height_delta_m;
  return p;
}

// Per-step blend factors of the actuator stages, 1 - exp(-dt / tau) (1 for tau = 0); a delay
// is rolled out as kActuatorDelayStages first-order stages of delay / kActuatorDelayStages each.
inline constexpr int kActuatorDelayStages = 4;
struct ActuatorAlphas {
  float steer_delay, steer_lag, throttle_delay, throttle_lag;
};
inline ActuatorAlphas actuator_alphas(const EffectParams& e, float dt_s) noexcept {
  auto a = [dt_s](double tau) { return tau > 0 ? static_cast<float>(1.0 - std::exp(-dt_s / tau)) : 1.f; };
  return {a(e.steer_delay_s / kActuatorDelayStages), a(e.steer_lag_s), a(e.throttle_delay_s / kActuatorDelayStages),
          a(e.throttle_lag_s)};
}

}  // namespace mppi
