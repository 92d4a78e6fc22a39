#pragma once
// "Nominal + effects" around any other model of the library: WithEffects<DoubleTrack>,
// <FullVehicle>, <KinematicBicycle>, <AutoRallyNetwork> add the terms that `mppi-fit diagnose`
// names (the EffectParams of dynamics/corrected_single_track.hpp) around an unchanged base
// model, so that a diagnosis can start from any of them. The single-track model has its own
// exact class (CorrectedSingleTrack, effects inside its force balance); here they enter around
// the base:
//   - actuator effects (offsets, gain, delays, lags, voltage sag) transform the command first;
//   - tyre effects (tire_saturation, friction_change, load_transfer) change the base's
//     single-track core parameters (apply_effect_params), with a second base model for the grip
//     after a change (time is a state). Only for bases with such a core (the four-wheel
//     models); the kinematic bicycle and the network have no tyres, so these are refused;
//   - force effects (aero_drag, rolling_resistance, road_grade) add their acceleration to
//     v_x (and v_y where the base has a lateral velocity) after the base step (operator
//     splitting; the step is the plant's 2 ms). Mass: the base's own, or for bases without one
//     the AutoRally car's (SingleTrackParams defaults; the network models that car).
// State: the base's kNx, then time [s], then the steer and throttle actuator chains.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <type_traits>
#include <utility>

#include "dynamics/autorally_nn.hpp"
#include "dynamics/corrected_single_track.hpp"
#include "dynamics/double_track.hpp"
#include "dynamics/fast_trig.hpp"
#include "dynamics/full_vehicle.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "dynamics/pacejka.hpp"
#include "mppi/concepts.hpp"

namespace mppi {

// A base whose parameters hold a single-track core (mass, tyres, CG height): tyre effects apply.
template <class Base>
concept HasSingleTrackCore = requires(const Base& b) {
  { b.params().base } -> std::convertible_to<SingleTrackParams>;
};

template <VehicleDynamics Base>
class WithEffects {
 public:
  static constexpr bool kTyreEffects = HasSingleTrackCore<Base>;
  static constexpr bool kLateralVelocity = !std::is_same_v<Base, KinematicBicycle>;  // it pins v_y = 0
  static constexpr int kChain = CorrectedSingleTrack::kChain;
  static constexpr int kTime = Base::kNx;
  static constexpr int kSteerChain = kTime + 1;
  static constexpr int kThrottleChain = kSteerChain + kChain;
  static constexpr int kNx = kThrottleChain + kChain;
  static constexpr int kNu = 2;
  static constexpr int kOmega = [] {  // wheel speeds, as in the base (-1: none)
    if constexpr (requires { Base::kOmega; }) return Base::kOmega;
    else return -1;
  }();

  // Throws mppi::Error if the effects are not valid, make the base invalid, or need tyres the
  // base does not have.
  explicit WithEffects(const Base& nominal, const EffectParams& effects = {})
      : nominal_(nominal), effects_(validated(effects)), before_(with_core(nominal, effects, 1.0)),
        after_(with_core(nominal, effects, effects.grip_scale)) {
    double m = SingleTrackParams{}.mass_kg, g = SingleTrackParams{}.gravity_mps2;
    if constexpr (kTyreEffects) {
      m = nominal_.params().base.mass_kg;
      g = nominal_.params().base.gravity_mps2;
    }
    drag_per_kg_ = static_cast<float>(effects_.aero_drag_kgpm / m);
    roll_per_kg_ = static_cast<float>(effects_.rolling_force_N / m);
    visc_per_kg_ = static_cast<float>(effects_.rolling_viscous_Nspm / m);
    grade_x_ = static_cast<float>(g * effects_.grade_x);
    grade_y_ = static_cast<float>(g * effects_.grade_y);
    change_time_ = static_cast<float>(effects_.grip_change_time_s);
    grip_changes_ = effects_.grip_scale != 1.0;
  }

  const Base& nominal() const { return nominal_; }
  const EffectParams& effects() const { return effects_; }
  std::size_t scratch_floats(int w) const { return before_.scratch_floats(w); }

  void advance_actuators(float* x, float steer, float throttle, float dt_s) const noexcept {
    const ActuatorAlphas al = actuator_alphas(effects_, dt_s);
    CorrectedSingleTrack::advance_chain(x + kSteerChain, steer, al.steer_delay, al.steer_lag);
    CorrectedSingleTrack::advance_chain(x + kThrottleChain, throttle, al.throttle_delay, al.throttle_lag);
  }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* scratch) const noexcept {
    const ActuatorAlphas al = actuator_alphas(effects_, dt_s);
    const float gain = static_cast<float>(effects_.steer_gain), offset = static_cast<float>(effects_.steer_offset);
    const float sag = static_cast<float>(effects_.voltage_sag), thr_offset = static_cast<float>(effects_.throttle_offset);
    float applied[kNu * W];  // the command the base model sees, per lane
    float vx0[W], yaw0[W];
    int before_lanes = 0;
    for (int j = 0; j < W; ++j) {
      float chain_s[kChain], chain_t[kChain];
      for (int i = 0; i < kChain; ++i) {
        chain_s[i] = x[kSteerChain + i][j];
        chain_t[i] = x[kThrottleChain + i][j];
      }
      const float s = CorrectedSingleTrack::advance_chain(chain_s, u[control::kSteer][j], al.steer_delay, al.steer_lag);
      const float t = CorrectedSingleTrack::advance_chain(chain_t, u[control::kThrottle][j], al.throttle_delay, al.throttle_lag);
      for (int i = 0; i < kChain; ++i) {
        x[kSteerChain + i][j] = chain_s[i];
        x[kThrottleChain + i][j] = chain_t[i];
      }
      const float t_pos = std::max(t, 0.f);
      applied[control::kSteer * W + j] = gain * s + offset;
      applied[control::kThrottle * W + j] = t + thr_offset - sag * t_pos * t_pos;
      vx0[j] = x[state::kVx][j];
      yaw0[j] = x[state::kYaw][j];
      before_lanes += grip_changes_ && x[kTime][j] < change_time_;
    }
    const Batch<Base::kNx, W> xb{x.data};
    const ConstBatch<Base::kNu, W> ub{applied};
    if (before_lanes == 0) {
      after_.template step<W>(xb, ub, dt_s, scratch);
    } else if (before_lanes == W) {
      before_.template step<W>(xb, ub, dt_s, scratch);
    } else {  // lanes on both sides of a grip change: step both, keep each lane's own
      float copy[Base::kNx * W];
      std::copy(x.data, x.data + Base::kNx * W, copy);
      before_.template step<W>(Batch<Base::kNx, W>{copy}, ub, dt_s, scratch);
      after_.template step<W>(xb, ub, dt_s, scratch);
      for (int j = 0; j < W; ++j)
        if (x[kTime][j] < change_time_)
          for (int i = 0; i < Base::kNx; ++i) x[i][j] = copy[i * W + j];
    }
    for (int j = 0; j < W; ++j) {
      const float vx = vx0[j];
      float sy, cy;
      fast_sincos(yaw0[j], &sy, &cy);
      const float ax = -drag_per_kg_ * vx * std::abs(vx) - roll_per_kg_ * phys::tanh(vx * 2.f) - visc_per_kg_ * vx -
                       (grade_x_ * cy + grade_y_ * sy);
      const float ay = -(-grade_x_ * sy + grade_y_ * cy);
      x[state::kVx][j] += ax * dt_s;
      if constexpr (kLateralVelocity) x[state::kVy][j] += ay * dt_s;
      x[kTime][j] += dt_s;
    }
  }

  // The base's start state; time 0; actuators at rest.
  void init_state(const VehicleState& s, float* x) const {
    std::fill(x, x + kNx, 0.f);
    after_.init_state(s, x);
  }

  // Sets both actuator chains to a steady command (as if it had been held for long).
  static void set_actuators(float* x, float steer, float throttle) noexcept {
    std::fill(x + kSteerChain, x + kSteerChain + kChain, steer);
    std::fill(x + kThrottleChain, x + kThrottleChain + kChain, throttle);
  }

 private:
  static Base with_core(const Base& b, const EffectParams& e, double grip) {
    if constexpr (kTyreEffects) {
      auto p = b.params();
      p.base = apply_effect_params(p.base, e, grip);
      return Base(p);
    } else {
      if (e.tyre_peak_scale != 1.0 || e.tyre_stiffness_scale != 1.0 || e.grip_scale != 1.0 || e.cg_height_delta_m != 0.0)
        throw Error("WithEffects: tire_saturation, friction_change and load_transfer need a tyre model; this base "
                    "model has none");
      return b;
    }
  }
  static const EffectParams& validated(const EffectParams& e) {
    std::string why;
    if (!e.is_valid(&why)) throw Error("WithEffects: invalid effect parameters: " + why);
    return e;
  }

  Base nominal_;
  EffectParams effects_;
  Base before_, after_;
  float drag_per_kg_ = 0, roll_per_kg_ = 0, visc_per_kg_ = 0, grade_x_ = 0, grade_y_ = 0, change_time_ = 0;
  bool grip_changes_ = false;
};

using DoubleTrackWithEffects = WithEffects<DoubleTrack>;
using FullVehicleWithEffects = WithEffects<FullVehicle>;
using KinematicWithEffects = WithEffects<KinematicBicycle>;
using AutoRallyNetworkWithEffects = WithEffects<AutoRallyNetwork>;

}  // namespace mppi
