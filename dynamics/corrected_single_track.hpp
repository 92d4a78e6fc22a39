#pragma once
// "Nominal + effects": the single-track model (dynamics/single_track.hpp) with the physical
// terms that `mppi-fit diagnose` names and fits (docs/DIAGNOSE.md). Every effect is off at its
// default value, so CorrectedSingleTrack with default EffectParams steps exactly like
// SingleTrack (plus 11 bookkeeping states). The same class is the synthetic truth plant of the
// concealed-effect generator and the corrected controller model that mppi-sim loads
// (`--model corrected --model-params file.yaml`, `--plant corrected --plant-params file.yaml`).
//
// Effects (their ids in reports and files):
//   steer_offset, steer_gain    delta = (gain * s_applied + offset) * max_steer
//   throttle_offset             throttle u_applied + b (a motor dead band when b < 0)
//   steer_delay, throttle_delay pure delays, rolled out as a chain of kDelayStages first-order
//                               stages of delay/kDelayStages each (an Erlang approximation the
//                               controller can integrate at any step; exact discretisation)
//   steer_lag, throttle_lag     first-order actuators, time constant tau
//   aero_drag                   extra force -c vx |vx|
//   rolling_resistance          extra force -(F0 tanh(vx / 0.5) + b vx)
//   tire_saturation             Magic Formula peak D -> k D, B -> s B / k: friction limit x k,
//                               cornering stiffness (B C D) x s
//   friction_change             grip (D, Sv) x g from time t_change on (time is a state)
//   load_transfer               CG height h -> h + dh (pitch load transfer)
//   motor_voltage_sag           throttle u -> u - k max(u, 0)^2 (battery sag under current)
//   road_grade                  a tilted plane z = gx x + gy y: force -m g (gx cos yaw + gy sin yaw)
// State: SingleTrack's 9, then time [s], then per channel (steer, throttle) kDelayStages delay
// stages followed by one lag stage (the lag stage's output is the applied command).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "dynamics/single_track.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi {

struct EffectParams {
  double steer_offset = 0.0;         // steer_offset: added to the applied steer [-]
  double steer_gain = 1.0;           // steer_gain: scale of the applied steer [-]
  double throttle_offset = 0.0;      // throttle_offset: added to the applied throttle (dead band) [-]
  double steer_delay_s = 0.0;        // steer_delay: pure delay [s]
  double throttle_delay_s = 0.0;     // throttle_delay: pure delay [s]
  double steer_lag_s = 0.0;          // steer_lag: first-order time constant [s]
  double throttle_lag_s = 0.0;       // throttle_lag: first-order time constant [s]
  double aero_drag_kgpm = 0.0;       // aero_drag: extra c [N s^2/m^2] in -c vx |vx|
  double rolling_force_N = 0.0;      // rolling_resistance: extra Coulomb force F0 [N]
  double rolling_viscous_Nspm = 0.0; // rolling_resistance: extra viscous b [N s/m]
  double tyre_peak_scale = 1.0;      // tire_saturation: k in D -> k D, B -> s B / k [-]
  double tyre_stiffness_scale = 1.0; // tire_saturation: s, cornering stiffness factor [-]
  double grip_scale = 1.0;           // friction_change: grip factor g after the change [-]
  double grip_change_time_s = 0.0;   // friction_change: time of the change [s] (time state)
  double cg_height_delta_m = 0.0;    // load_transfer: dh added to the CG height [m]
  double voltage_sag = 0.0;          // motor_voltage_sag: k in u - k max(u,0)^2 [-]
  double grade_x = 0.0;              // road_grade: slope dz/dx of the ground plane [-]
  double grade_y = 0.0;              // road_grade: slope dz/dy of the ground plane [-]

  bool is_valid(std::string* why) const {
    auto fail = [&](const std::string& m) {
      if (why) *why = m;
      return false;
    };
    const double all[] = {steer_offset, steer_gain, throttle_offset, steer_delay_s, throttle_delay_s, steer_lag_s,
                          throttle_lag_s, aero_drag_kgpm, rolling_force_N, rolling_viscous_Nspm,
                          tyre_peak_scale, tyre_stiffness_scale, grip_scale, grip_change_time_s, cg_height_delta_m,
                          voltage_sag, grade_x, grade_y};
    for (double v : all)
      if (!std::isfinite(v)) return fail("every effect parameter must be finite");
    if (steer_delay_s < 0 || throttle_delay_s < 0 || steer_lag_s < 0 || throttle_lag_s < 0)
      return fail("delays and lags must be >= 0");
    if (!(tyre_peak_scale > 0.05 && grip_scale > 0.05 && tyre_stiffness_scale > 0.05)) return fail("tyre_peak_scale and grip_scale must be > 0.05");
    if (!(std::abs(grade_x) < 0.5 && std::abs(grade_y) < 0.5)) return fail("|grade| must be < 0.5");
    if (!(voltage_sag >= 0 && voltage_sag < 1)) return fail("voltage_sag must be in [0, 1)");
    return true;
  }
};

// The nominal single-track parameters with the effects that change them (tyre, CG height).
// `grip` scales the friction curve (D and Sv).
inline SingleTrackParams apply_effect_params(SingleTrackParams p, const EffectParams& e, double grip) {
  p.tyre.D *= e.tyre_peak_scale * grip;
  p.tyre.Sv *= grip;
  p.tyre.B *= e.tyre_stiffness_scale / e.tyre_peak_scale;
  p.cg_height_m += e.cg_height_delta_m;
  return p;
}

// Per-step blend factors of the actuator stages, 1 - exp(-dt / tau) (1 for tau = 0); a delay
// is rolled out as kDelayStages first-order stages of delay / kDelayStages each.
inline constexpr int kActuatorDelayStages = 4;
struct ActuatorAlphas {
  float steer_delay, steer_lag, throttle_delay, throttle_lag;
};
inline ActuatorAlphas actuator_alphas(const EffectParams& e, float dt_s) noexcept {
  auto a = [dt_s](double tau) { return tau > 0 ? static_cast<float>(1.0 - std::exp(-dt_s / tau)) : 1.f; };
  return {a(e.steer_delay_s / kActuatorDelayStages), a(e.steer_lag_s), a(e.throttle_delay_s / kActuatorDelayStages),
          a(e.throttle_lag_s)};
}

class CorrectedSingleTrack {
 public:
  static constexpr int kDelayStages = kActuatorDelayStages;
  static constexpr int kTime = SingleTrack::kNx;                     // 9
  static constexpr int kSteerChain = kTime + 1;                      // 10..14
  static constexpr int kThrottleChain = kSteerChain + kDelayStages + 1;  // 15..19
  static constexpr int kChain = kDelayStages + 1;
  static constexpr int kNx = kThrottleChain + kChain;                // 20
  static constexpr int kNu = 2;

  // Throws mppi::Error if the parameters are not valid (nominal, effects, or the combination).
  explicit CorrectedSingleTrack(const SingleTrackParams& nominal = {}, const EffectParams& effects = {})
      : nominal_(nominal), effects_(effects) {
    std::string why;
    if (!nominal_.is_valid(&why)) throw Error("CorrectedSingleTrack: invalid nominal parameters: " + why);
    if (!effects_.is_valid(&why)) throw Error("CorrectedSingleTrack: invalid effect parameters: " + why);
    const SingleTrackParams before = apply_effect_params(nominal_, effects_, 1.0);
    const SingleTrackParams after = apply_effect_params(nominal_, effects_, effects_.grip_scale);
    if (!before.is_valid(&why) || !after.is_valid(&why))
      throw Error("CorrectedSingleTrack: the effects make the model invalid: " + why);
    before_ = SingleTrackCoeffs<float>::from(before);
    after_ = SingleTrackCoeffs<float>::from(after);
    const double m = nominal_.mass_kg;
    drag_per_kg_ = static_cast<float>(effects_.aero_drag_kgpm / m);
    roll_per_kg_ = static_cast<float>(effects_.rolling_force_N / m);
    visc_per_kg_ = static_cast<float>(effects_.rolling_viscous_Nspm / m);
    grade_x_ = static_cast<float>(nominal_.gravity_mps2 * effects_.grade_x);
    grade_y_ = static_cast<float>(nominal_.gravity_mps2 * effects_.grade_y);
    change_time_ = static_cast<float>(effects_.grip_change_time_s);
    gain_ = static_cast<float>(effects_.steer_gain);
    offset_ = static_cast<float>(effects_.steer_offset);
    sag_ = static_cast<float>(effects_.voltage_sag);
    thr_offset_ = static_cast<float>(effects_.throttle_offset);
  }

  const SingleTrackParams& nominal() const { return nominal_; }
  const EffectParams& effects() const { return effects_; }
  std::size_t scratch_floats(int) const { return 0; }

  ActuatorAlphas alphas(float dt_s) const noexcept { return actuator_alphas(effects_, dt_s); }

  // Advances one actuator chain (kChain floats) by one step with input u; returns the output.
  static float advance_chain(float* chain, float u, float a_delay, float a_lag) noexcept {
    float in = u;
    for (int i = 0; i < kDelayStages; ++i) {
      chain[i] += a_delay * (in - chain[i]);
      in = chain[i];
    }
    chain[kDelayStages] += a_lag * (in - chain[kDelayStages]);
    return chain[kDelayStages];
  }

  // Actuator chains only, one state (used to prime them from a command history).
  void advance_actuators(float* x, float steer, float throttle, float dt_s) const noexcept {
    const ActuatorAlphas al = alphas(dt_s);
    advance_chain(x + kSteerChain, steer, al.steer_delay, al.steer_lag);
    advance_chain(x + kThrottleChain, throttle, al.throttle_delay, al.throttle_lag);
  }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* /*scratch*/) const noexcept {
    const ActuatorAlphas al = alphas(dt_s);
    const SingleTrackCoeffs<float> kb = before_, ka = after_;
    const float drag = drag_per_kg_, roll = roll_per_kg_, visc = visc_per_kg_;
    const float gx = grade_x_, gy = grade_y_, tc = change_time_, gain = gain_, offset = offset_,
                sag = sag_, thr_offset = thr_offset_;
    const float* ps = u[control::kSteer];
    const float* pt = u[control::kThrottle];
    for (int j = 0; j < W; ++j) {
      float chain_s[kChain], chain_t[kChain];
      for (int i = 0; i < kChain; ++i) {
        chain_s[i] = x[kSteerChain + i][j];
        chain_t[i] = x[kThrottleChain + i][j];
      }
      const float steer_applied = advance_chain(chain_s, ps[j], al.steer_delay, al.steer_lag);
      const float thr_applied = advance_chain(chain_t, pt[j], al.throttle_delay, al.throttle_lag);
      for (int i = 0; i < kChain; ++i) {
        x[kSteerChain + i][j] = chain_s[i];
        x[kThrottleChain + i][j] = chain_t[i];
      }
      const float steer = gain * steer_applied + offset;
      const float thr_pos = std::max(thr_applied, 0.f);
      const float thr = thr_applied + thr_offset - sag * thr_pos * thr_pos;
      const float vx = x[state::kVx][j], vy = x[state::kVy][j], r = x[state::kYawRate][j];
      const float yaw = x[state::kYaw][j];
      const float t = x[kTime][j];
      SingleTrackTerms<float> e;
      single_track_terms(t < tc ? kb : ka, vx, vy, r, x[SingleTrack::kOmegaFront][j],
                         x[SingleTrack::kOmegaRear][j], steer, thr, &e);
      float sy, cy;
      fast_sincos(yaw, &sy, &cy);
      const float extra_ax = -drag * vx * std::abs(vx) - roll * phys::tanh(vx * 2.f) - visc * vx -
                             (gx * cy + gy * sy);
      const float extra_ay = -(-gx * sy + gy * cy);  // grade force along body y
      x[state::kX][j] += (cy * vx - sy * vy) * dt_s;
      x[state::kY][j] += (sy * vx + cy * vy) * dt_s;
      x[state::kYaw][j] += r * dt_s;
      x[state::kVx][j] = vx + (e.dvx_mps2 + extra_ax) * dt_s;
      x[state::kVy][j] = vy + (e.dvy_mps2 + extra_ay) * dt_s;
      x[state::kYawRate][j] = r + e.dyaw_rate_radps2 * dt_s;
      x[SingleTrack::kOmegaFront][j] += e.domega_front_radps2 * dt_s;
      x[SingleTrack::kOmegaRear][j] += e.domega_rear_radps2 * dt_s;
      x[kTime][j] = t + dt_s;
    }
  }

  // Common state copied; roll 0; wheels rolling (omega = vx / R); time 0; actuators at rest.
  void init_state(const VehicleState& s, float* x) const {
    const auto common = s.to_array();
    std::fill(x, x + kNx, 0.f);
    std::copy(common.begin(), common.end(), x);
    x[state::kRoll] = 0.f;
    x[SingleTrack::kOmegaFront] = x[SingleTrack::kOmegaRear] =
        static_cast<float>(s.vx_mps / nominal_.wheel_radius_m);
  }

  // Sets both actuator chains to a steady command (as if it had been held for long).
  static void set_actuators(float* x, float steer, float throttle) noexcept {
    std::fill(x + kSteerChain, x + kSteerChain + kChain, steer);
    std::fill(x + kThrottleChain, x + kThrottleChain + kChain, throttle);
  }

 private:
  SingleTrackParams nominal_;
  EffectParams effects_;
  SingleTrackCoeffs<float> before_{}, after_{};
  float drag_per_kg_ = 0, roll_per_kg_ = 0, visc_per_kg_ = 0, grade_x_ = 0, grade_y_ = 0;
  float change_time_ = 0, gain_ = 1, offset_ = 0, sag_ = 0, thr_offset_ = 0;
};

// The corrected-model file (YAML; written by mppi-fit diagnose, docs/DIAGNOSE.md):
//   model: corrected
//   nominal: single-track
//   nominal_params: { <single-track keys, as in data/config/autorally_single_track.yaml> }
//   effects: { <EffectParams field>: value, ... }
// Unknown keys, non-numbers and invalid values throw mppi::Error naming the file and key.
//   nominal: double-track | full-vehicle | kinematic | autorally-nn (then nominal_params holds
//   that model's keys, for the network `network_npz: PATH` (empty = the shipped AutoRally
//   network), and the effects wrap it: WithEffects<...>, dynamics/with_effects.hpp)
struct CorrectedModelFile {
  std::string nominal_model = mppi::models::SingleTrackModel::kName;  // one of kCorrectedNominalModels
  SingleTrackParams nominal;          // single-track: the model; four-wheel: their core
  DoubleTrackParams double_track;     // nominal_model == double-track
  FullVehicleParams full_vehicle;     // nominal_model == full-vehicle
  KinematicBicycleParams kinematic;   // nominal_model == kinematic
  std::string network_npz;            // nominal_model == autorally-nn ("" = the shipped network)
  EffectParams effects;
  std::vector<std::string> selected;  // effect ids (informational, `selected:` list)
};
// The registered models a corrected-model file can have as its nominal (the file has a
// parameter section for each of them).
using CorrectedNominalModels = TypeList<models::SingleTrackModel, models::DoubleTrackModel, models::FullVehicleModel,
                                        models::Kinematic, models::AutoRallyNetworkModel>;
inline const std::string kCorrectedNominalModels = names_of(CorrectedNominalModels{});
inline bool is_corrected_nominal_model(const std::string& name) {
  return visit_by_name(CorrectedNominalModels{}, name, []<class D>() {});
}
CorrectedModelFile load_corrected_model(const std::string& path);
CorrectedModelFile corrected_model_from_yaml(const std::string& text, const std::string& source);
// YAML text of a corrected-model file.
std::string corrected_model_to_yaml(const CorrectedModelFile& model, const std::string& comment = "");

}  // namespace mppi
