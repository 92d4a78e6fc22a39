#pragma once
// "Nominal + effects" around any model of the library: WithEffects<SingleTrack>,
// <DoubleTrack>, <FullVehicle>, <KinematicBicycle>, <AutoRallyNetwork> add the terms that
// `mppi-fit diagnose` names and fits (the effect table, dynamics/effects.hpp) around an
// unchanged base model. The same class is the synthetic truth plant of the concealed-effect
// generator and the corrected model that mppi-sim loads (`--model corrected`). Every effect is
// off at its default value, so WithEffects<M> with default EffectParams steps exactly like M
// (plus the bookkeeping states). Each effect enters through its hook:
//   - actuator: offsets, gains, steering map, delays, lags, rate limits, backlash and voltage
//     sag transform the command first; a speed loop turns a speed command into the throttle
//     from the driven wheels' rim speed;
//   - chassis: tire_saturation, friction_change, grip_patch, load_transfer, payload and
//     motor_speed change the base's single-track core parameters (apply_effect_params), with a
//     second base model for the other grip: after a change (time is a state) or on the patch's
//     discs (across a disc's edge the two steps are blended). Only for bases with such a core (the
//     single-track and four-wheel models); the kinematic bicycle and the network have none, so
//     these are refused;
//   - force: aero_drag, rolling_resistance, road_grade and ground_bump add an acceleration along
//     the body axes, and the rolling resistance of the steered front wheels a yaw acceleration
//     (it acts along each wheel, so a turned front wheel pulls the nose back). A base that offers
//     step_with_body_accel (the single-track model) takes them inside its force balance; for the
//     others they are added to v_x (and v_y and the yaw rate where the base has a lateral velocity)
//     after the base step (operator splitting over one plant step). Mass, yaw inertia, axle
//     positions and steering range: the base's own, or for bases without them the AutoRally car's
//     (SingleTrackParams defaults; the network models that car).
// State: the base's kNx, then time [s], then the steer and throttle actuator chains
// (kActuatorDelayStages delay stages, one lag stage with the rate limit, one play stage for the
// backlash, whose output is applied), then the speed loop's integral of its speed error [m], then
// the states of the effects declared in files of their own (dynamics/effects/effect_registry.hpp),
// whose terms it folds over: tyre_relaxation adds its lag to the force hook.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "base/batch.hpp"
#include "base/fast_math.hpp"
#include "dynamics/autorally_nn.hpp"
#include "dynamics/double_track.hpp"
#include "dynamics/effects.hpp"
#include "dynamics/fast_trig.hpp"
#include "dynamics/full_vehicle.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "dynamics/pacejka.hpp"
#include "dynamics/single_track.hpp"
#include "mppi/concepts.hpp"

namespace mppi {

// The single-track core of a model's parameters (mass, tyres, CG height), where it has one.
inline const SingleTrackParams& single_track_core(const SingleTrackParams& p) { return p; }
inline SingleTrackParams& single_track_core(SingleTrackParams& p) { return p; }
template <class P>
  requires requires(P& p) { { p.base } -> std::convertible_to<SingleTrackParams>; }
auto& single_track_core(P& p) { return p.base; }

// A base whose parameters hold a single-track core: chassis effects apply.
template <class Base>
concept HasSingleTrackCore = requires(const Base& b) {
  { single_track_core(b.params()) } -> std::convertible_to<SingleTrackParams>;
};

// A base that takes extra body-axis accelerations inside its force balance.
template <class Base>
concept HasBodyAccelHook = requires(const Base& b, Batch<Base::kNx, 1> x, ConstBatch<Base::kNu, 1> u, float* a) {
  b.template step_with_body_accel<1>(x, u, 0.f, a, a, a, a);
};

template <VehicleDynamics Base>
class WithEffects {
 public:
  static constexpr bool kChassisEffects = HasSingleTrackCore<Base>;
  static constexpr bool kLateralVelocity = !std::is_same_v<Base, KinematicBicycle>;  // it pins v_y = 0
  static constexpr int kDelayStages = kActuatorDelayStages;
  static constexpr int kChain = kDelayStages + 2;
  static constexpr int kTime = Base::kNx;
  static constexpr int kSteerChain = kTime + 1;
  static constexpr int kThrottleChain = kSteerChain + kChain;
  static constexpr int kSpeedLoopIntegral = kThrottleChain + kChain;
  static constexpr int kDeclaredStates = kSpeedLoopIntegral + 1;  // the declared effects' states
  static constexpr int kNx = kDeclaredStates + effects::StatesOfAll<effects::DeclaredEffects>::kCount;
  static constexpr int kNu = 2;
  static constexpr int kOmega = [] {  // wheel speeds, as in the base (-1: none)
    if constexpr (requires { Base::kOmega; }) return Base::kOmega;
    else return -1;
  }();

  // Throws mppi::Error if the effects are not valid, make the base invalid, or need tyres the
  // base does not have.
  explicit WithEffects(const Base& nominal = Base(), const EffectParams& effects = {})
      : nominal_(nominal), effects_(validated(effects)), before_(with_core(nominal, effects, 1.0)),
        after_(with_core(nominal, effects, other_grip(effects))) {
    SingleTrackParams car;  // the AutoRally car, for bases without a mass
    if constexpr (kChassisEffects) car = single_track_core(after_.params());  // payload included
    const double m = car.mass_kg, g = car.gravity_mps2;
    drag_per_kg_ = static_cast<float>(effects_.aero_drag_kgpm / m);
    roll_per_kg_ = static_cast<float>(effects_.rolling_force_N / m);
    visc_per_kg_ = static_cast<float>(effects_.rolling_viscous_Nspm / m);
    rolling_ = effects_.rolling_force_N != 0.0 || effects_.rolling_viscous_Nspm != 0.0;
    // The resistance is shared by the axles as the static load is (front: l_r / L).
    front_roll_share_ = static_cast<float>(car.cg_to_rear_axle_m / (car.cg_to_front_axle_m + car.cg_to_rear_axle_m));
    front_arm_m_ = static_cast<float>(car.cg_to_front_axle_m);
    mass_per_yaw_inertia_ = static_cast<float>(m / car.yaw_inertia_kgm2);
    max_steer_rad_ = static_cast<float>(car.max_steer_rad);
    if constexpr (kChassisEffects) {  // motor_freewheel, drag_brake: in units of the normalised command
      esc_ = effects_.motor_freewheel_share > 0.0 || effects_.drag_brake_mps2 > 0.0;
      freewheel_per_mps_ = static_cast<float>(effects_.motor_freewheel_share / car.no_load_speed_mps);
      drag_brake_cmd_ = static_cast<float>(effects_.drag_brake_mps2 * m * car.wheel_radius_m / car.stall_torque_Nm);
      brake_ratio_ = static_cast<float>(car.brake_torque_ratio);
      inv_brake_ratio_ = car.brake_torque_ratio > 0.0 ? static_cast<float>(1.0 / car.brake_torque_ratio) : 0.f;
      wheel_radius_ = static_cast<float>(car.wheel_radius_m);
      front_drive_ = static_cast<float>(car.front_drive_share);
    }
    grade_x_ = static_cast<float>(g * effects_.grade_x);
    grade_y_ = static_cast<float>(g * effects_.grade_y);
    bump_ = effects_.bump_height_m != 0.0 && effects_.bump_radius_m > 0.0;
    bump_x_ = static_cast<float>(effects_.bump_x_m);
    bump_y_ = static_cast<float>(effects_.bump_y_m);
    bump_r_ = static_cast<float>(effects_.bump_radius_m);
    // dz/dd = -h (pi / 2R) sin(pi d / R); times g for the acceleration
    bump_slope_ = bump_ ? static_cast<float>(-g * effects_.bump_height_m * std::numbers::pi / (2.0 * effects_.bump_radius_m)) : 0.f;
    change_time_ = static_cast<float>(effects_.grip_change_time_s);
    grip_changes_ = effects_.grip_scale != 1.0;
    patch_ = effects_.patch_grip_scale != 1.0;
    if (patch_) {
      discs_[discs_n_++] = {static_cast<float>(effects_.patch_x_m), static_cast<float>(effects_.patch_y_m),
                            static_cast<float>(effects_.patch_radius_m)};
      for (const OptionalDisc& d : kOptionalPatchDiscs)
        if (effects_.*(d.radius) > 0.0)
          discs_[discs_n_++] = {static_cast<float>(effects_.*(d.x)), static_cast<float>(effects_.*(d.y)),
                                static_cast<float>(effects_.*(d.radius))};
    }
    gain_ = static_cast<float>(effects_.steer_gain);
    offset_ = static_cast<float>(effects_.steer_offset);
    steer_cubic_ = static_cast<float>(effects_.steer_cubic);
    left_gain_ = static_cast<float>(1.0 + effects_.steer_asymmetry);
    right_gain_ = static_cast<float>(1.0 - effects_.steer_asymmetry);
    throttle_gain_ = static_cast<float>(effects_.throttle_gain);
    thr_offset_ = static_cast<float>(effects_.throttle_offset);
    sag_ = static_cast<float>(effects_.voltage_sag);
    speed_loop_ = effects_.speed_loop_top_speed_mps > 0.0;
    loop_top_speed_mps_ = static_cast<float>(effects_.speed_loop_top_speed_mps);
    loop_gain_per_mps_ = static_cast<float>(effects_.speed_loop_gain);
    loop_integral_gain_per_m_ = static_cast<float>(effects_.speed_loop_integral_gain);
    loop_feedforward_per_mps_ = static_cast<float>(1.0 / car.no_load_speed_mps);
    if constexpr (kChassisEffects)
      for_each_type(effects::DeclaredEffects{}, [&]<class E>() {
        std::get<typename E::Term>(declared_) =
            typename E::Term(static_cast<const typename E::Params&>(effects_), single_track_core(before_.params()));
      });
  }

  const Base& nominal() const { return nominal_; }
  const EffectParams& effects() const { return effects_; }
  std::size_t scratch_floats(int w) const { return before_.scratch_floats(w); }

  // Advances one actuator chain (kChain states: the delay stages, the lag with its rate limit, the
  // play) of W lanes by one step: the chain of lane j is x[first + i][j], its input u[j]; the
  // outputs (what is applied) go to out[j].
  template <int W>
  static void advance_chain_lanes(Batch<kNx, W> x, int first, const float* u, const ChainCoeffs& k,
                                  float* out) noexcept {
    float in[W];
    std::copy(u, u + W, in);
    for (int i = 0; i < kDelayStages; ++i) {
      float* const stage = x[first + i];
      MPPI_SIMD_LOOP
      for (int j = 0; j < W; ++j) {
        stage[j] += k.a_delay * (in[j] - stage[j]);
        in[j] = stage[j];
      }
    }
    float* const lag = x[first + kDelayStages];
    float* const play = x[first + kDelayStages + 1];
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) lag[j] += std::clamp(k.a_lag * (in[j] - lag[j]), -k.max_step, k.max_step);
    if (k.backlash > 0.f) {
      const float half = 0.5f * k.backlash;
      MPPI_SIMD_LOOP
      for (int j = 0; j < W; ++j) play[j] = std::clamp(play[j], lag[j] - half, lag[j] + half);
    } else {
      std::copy(lag, lag + W, play);
    }
    std::copy(play, play + W, out);
  }

  // Actuator chains only, one state (used to prime them from a command history).
  void advance_actuators(float* x, float steer, float throttle, float dt_s) const noexcept {
    const ActuatorCoeffs k = actuator_coeffs(effects_, dt_s);
    const Batch<kNx, 1> lane{x};
    float applied;
    advance_chain_lanes<1>(lane, kSteerChain, &steer, k.steer, &applied);
    advance_chain_lanes<1>(lane, kThrottleChain, &throttle, k.throttle, &applied);
  }

  // The command the base model sees from the chains' outputs.
  float applied_steer(float s) const noexcept {
    const float mapped = s + steer_cubic_ * s * s * s;
    return gain_ * (mapped * (mapped > 0.f ? left_gain_ : right_gain_)) + offset_;
  }
  float applied_throttle(float t) const noexcept {
    const float t_pos = std::max(t, 0.f);
    return throttle_gain_ * t + thr_offset_ - sag_ * t_pos * t_pos;
  }

  // speed_loop: the throttle a low-level loop sets for the speed command u (the speed V u), from
  // the driven wheels' rim speed v: the throttle that holds V u on the DC-motor line without load
  // (V u / v_nl), plus k e + k_i (integral of e), e = V u - v. The integral [m] advances by e dt
  // unless that would take the throttle past +-1 (anti-windup).
  float speed_loop_throttle(float u, float rim_mps, float* integral_m, float dt_s) const noexcept {
    const float target_mps = loop_top_speed_mps_ * u;
    const float error_mps = target_mps - rim_mps;
    const float without_integral = loop_feedforward_per_mps_ * target_mps + loop_gain_per_mps_ * error_mps;
    const float wound_m = *integral_m + error_mps * dt_s;
    const float wound = without_integral + loop_integral_gain_per_m_ * wound_m;
    if (wound > -1.f && wound < 1.f) *integral_m = wound_m;
    return std::clamp(without_integral + loop_integral_gain_per_m_ * *integral_m, -1.f, 1.f);
  }

  // motor_freewheel and drag_brake: the command u' that makes the base's motor law
  // T_stall (max(u', 0) + k_brake min(u', 0) - v / v_nl) give the ESC's torque
  //   T_stall (max(u, 0) + k_brake min(u, 0) - v / v_nl ((1 - f) + f |u|)) - m R a_db n(u) tanh(2 v),
  // n = 1 in the ESC's neutral band; v is the motor's rim speed (motor_rim_speed), as in the base's
  // law. So the tyres still limit the torque. A base without a brake (k_brake = 0) cannot brake:
  // the negative part is dropped.
  float esc_throttle(float u, float rim_mps) const noexcept {
    const float torque = std::max(u, 0.f) + brake_ratio_ * std::min(u, 0.f);
    const float duty = std::min(std::abs(u), 1.f);
    const float neutral = std::clamp((kEscNeutralEdge - std::abs(u)) / (kEscNeutralEdge - kEscNeutralFull), 0.f, 1.f);
    const float g = torque + freewheel_per_mps_ * (1.f - duty) * rim_mps -
                    drag_brake_cmd_ * neutral * phys::tanh(rim_mps * 2.f);
    return g >= 0.f ? g : g * inv_brake_ratio_;
  }
  // The driven wheels' rim speed of lane j as the base's motor sees it: omega_r R, or with a
  // share s of the drive on the front axle (s omega_f + (1 - s) omega_r) R.
  template <int W>
  float motor_rim_speed(Batch<kNx, W> x, int j) const noexcept {
    if constexpr (requires { Base::kOmegaRear; }) {
      return (front_drive_ * x[Base::kOmegaFront][j] + (1.f - front_drive_) * x[Base::kOmegaRear][j]) * wheel_radius_;
    } else if constexpr (kOmega >= 0) {  // four wheels: the differential carrier's speed
      return 0.5f * (x[kOmega + wheel::kLR][j] + x[kOmega + wheel::kRR][j]) * wheel_radius_;
    } else {
      return x[state::kVx][j];
    }
  }

  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt_s, float* scratch) const noexcept {
    const ActuatorCoeffs k = actuator_coeffs(effects_, dt_s);
    // Every stage below runs over all lanes at once (a SIMD loop per stage), in the order the
    // physics needs: actuator chains, command maps, then the forces from the start-of-step state.
    float applied[kNu * W];  // the command the base model sees, per lane
    float* const steer = applied + control::kSteer * W;
    float* const throttle = applied + control::kThrottle * W;
    float ax[W], ay[W];      // force hook: body-axis accelerations from the start-of-step state
    float yaw_accel[W];      // and the yaw acceleration [rad/s^2]
    float other_w[W];        // weight of the other grip (after a change, on the patch) per lane
    advance_chain_lanes<W>(x, kSteerChain, u[control::kSteer], k.steer, steer);
    advance_chain_lanes<W>(x, kThrottleChain, u[control::kThrottle], k.throttle, throttle);
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) steer[j] = applied_steer(steer[j]);
    if (speed_loop_)
      for (int j = 0; j < W; ++j)
        throttle[j] = speed_loop_throttle(throttle[j], motor_rim_speed<W>(x, j), &x[kSpeedLoopIntegral][j], dt_s);
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) throttle[j] = applied_throttle(throttle[j]);
    if (esc_) {
      MPPI_SIMD_LOOP
      for (int j = 0; j < W; ++j) throttle[j] = esc_throttle(throttle[j], motor_rim_speed<W>(x, j));
    }
    body_accelerations<W>(x, steer, ax, ay, yaw_accel);
    declared_body_accelerations<W>(x, steer, ax, ay, yaw_accel, dt_s);
    other_grip_weights<W>(x, other_w);
    int before_lanes = 0, blended_lanes = 0;
    for (int j = 0; j < W; ++j) {
      before_lanes += other_w[j] == 0.f;
      blended_lanes += other_w[j] > 0.f && other_w[j] < 1.f;
    }
    const Batch<Base::kNx, W> xb{x.data};
    const ConstBatch<Base::kNu, W> ub{applied};
    if (before_lanes == 0 && blended_lanes == 0) {
      base_step<W>(after_, xb, ub, dt_s, scratch, ax, ay, yaw_accel);
    } else if (before_lanes == W) {
      base_step<W>(before_, xb, ub, dt_s, scratch, ax, ay, yaw_accel);
    } else {  // lanes on both sides of a grip change or patch edge: step both, blend per lane
      float copy[Base::kNx * W];
      std::copy(x.data, x.data + Base::kNx * W, copy);
      base_step<W>(before_, Batch<Base::kNx, W>{copy}, ub, dt_s, scratch, ax, ay, yaw_accel);
      base_step<W>(after_, xb, ub, dt_s, scratch, ax, ay, yaw_accel);
      for (int j = 0; j < W; ++j) {
        const float w = other_w[j];
        if (w == 1.f) continue;
        for (int i = 0; i < Base::kNx; ++i)
          x[i][j] = w == 0.f ? copy[i * W + j] : w * x[i][j] + (1.f - w) * copy[i * W + j];
      }
    }
    for (int j = 0; j < W; ++j) x[kTime][j] += dt_s;
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
  // Weight of the other grip at each lane's time and place: 0 or 1 for a change in time; on the
  // patch's discs a logistic edge kPatchEdge_m wide, snapped to 0 / 1 where it is within 1e-3 of
  // them (so the car steps one base model away from the edge). Where discs overlap, the nearest
  // edge inward counts (the largest weight).
  static constexpr float kPatchEdge_m = 0.25f;
  template <int W>
  void other_grip_weights(Batch<kNx, W> x, float* w) const noexcept {
    if (grip_changes_) {
      for (int j = 0; j < W; ++j) w[j] = x[kTime][j] < change_time_ ? 0.f : 1.f;
      return;
    }
    if (!patch_) {  // only the nominal grip: after_ == before_
      std::fill(w, w + W, 1.f);
      return;
    }
    float z[W];  // edge distance in edge widths, negative inside
    std::fill(z, z + W, 7.f);
    const float* const px = x[state::kX];
    const float* const py = x[state::kY];
    for (int i = 0; i < discs_n_; ++i) {
      const Disc d = discs_[i];
      MPPI_SIMD_LOOP
      for (int j = 0; j < W; ++j) {
        const float dx = px[j] - d.x_m, dy = py[j] - d.y_m;
        z[j] = std::min(z[j], (std::sqrt(dx * dx + dy * dy) - d.radius_m) / kPatchEdge_m);
      }
    }
    for (int j = 0; j < W; ++j) w[j] = z[j] > 6.9f ? 0.f : z[j] < -6.9f ? 1.f : 1.f / (1.f + std::exp(z[j]));
  }
  // Body-axis accelerations of the force hook from the start-of-step state: air drag, the
  // ground's slope (plane and bump) and rolling resistance; `steer` is the applied steer per lane.
  template <int W>
  void body_accelerations(Batch<kNx, W> x, const float* steer, float* ax, float* ay,
                          float* yaw_accel) const noexcept {
    float gx[W], gy[W];  // g x the ground's slope here (plane + bump)
    std::fill(gx, gx + W, grade_x_);
    std::fill(gy, gy + W, grade_y_);
    if (bump_)
      for (int j = 0; j < W; ++j) add_bump_slope(x[state::kX][j], x[state::kY][j], &gx[j], &gy[j]);
    const float* const vx = x[state::kVx];
    const float* const yaw = x[state::kYaw];
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      float sy, cy;
      fast_sincos(yaw[j], &sy, &cy);
      ax[j] = -drag_per_kg_ * vx[j] * std::abs(vx[j]) - (gx[j] * cy + gy[j] * sy);
      ay[j] = -(-gx[j] * sy + gy[j] * cy);
      yaw_accel[j] = 0.f;
    }
    if (rolling_) {
      MPPI_SIMD_LOOP
      for (int j = 0; j < W; ++j) add_rolling_resistance(x, j, steer[j], &ax[j], &ay[j], &yaw_accel[j]);
    }
  }
  // The declared effects' terms (dynamics/effects/effect_registry.hpp), each on its own states.
  template <int W>
  void declared_body_accelerations(Batch<kNx, W> x, const float* steer, float* ax, float* ay, float* yaw_accel,
                                   float dt_s) const noexcept {
    const BodyAccelLanes<W> lanes{x[state::kVx], x[state::kVy], x[state::kYawRate], steer, ax, ay, yaw_accel};
    for_each_type(effects::DeclaredEffects{}, [&]<class E>() {
      const auto& term = std::get<typename E::Term>(declared_);
      if (!term.active()) return;
      float* rows[E::kStates];
      for (int i = 0; i < E::kStates; ++i)
        rows[i] = x[kDeclaredStates + effects::StateOffset<E, effects::DeclaredEffects>::kValue + i];
      term.template add_body_accelerations<W>(lanes, rows, dt_s);
    });
  }
  // Rolling resistance F0 tanh(v / 0.5) + b v against each axle's rolling speed v, along its
  // wheel: the rear along the body's x axis, the front turned by the wheel angle delta, so that
  // steered front wheels also push the car sideways and turn its nose back (-l_f F_front sin delta).
  template <int W>
  void add_rolling_resistance(Batch<kNx, W> x, int j, float applied_steer, float* ax, float* ay,
                              float* yaw_accel) const noexcept {
    const float vx = x[state::kVx][j], vy = x[state::kVy][j], r = x[state::kYawRate][j];
    const float delta = std::clamp(applied_steer, -1.f, 1.f) * max_steer_rad_;
    float sd, cd;
    fast_sincos(delta, &sd, &cd);
    const float front_v = vx * cd + (vy + front_arm_m_ * r) * sd;  // the front wheel's rolling speed
    auto per_kg = [this](float v) { return roll_per_kg_ * phys::tanh(v * 2.f) + visc_per_kg_ * v; };
    const float front = front_roll_share_ * per_kg(front_v), rear = (1.f - front_roll_share_) * per_kg(vx);
    *ax -= front * cd + rear;
    *ay -= front * sd;
    *yaw_accel -= mass_per_yaw_inertia_ * front_arm_m_ * front * sd;
  }
  // Adds g x the bump's slope (dz/dx, dz/dy) at (x, y) to (gx, gy).
  void add_bump_slope(float x_m, float y_m, float* gx, float* gy) const noexcept {
    const float dx = x_m - bump_x_, dy = y_m - bump_y_;
    const float d = std::sqrt(dx * dx + dy * dy);
    if (!(d < bump_r_) || d < 1e-6f) return;  // level beyond the radius; flat at the top
    const float along = bump_slope_ * std::sin(static_cast<float>(std::numbers::pi) * d / bump_r_) / d;
    *gx += along * dx;
    *gy += along * dy;
  }
  static double other_grip(const EffectParams& e) {
    if (e.grip_scale != 1.0 && e.patch_grip_scale != 1.0)
      throw Error("WithEffects: friction_change and grip_patch cannot be combined (one other grip)");
    return e.patch_grip_scale != 1.0 ? e.patch_grip_scale : e.grip_scale;
  }

  // One base step with the force hook: inside the base's force balance where it offers that,
  // else added after its step.
  template <int W>
  static void base_step(const Base& base, Batch<Base::kNx, W> x, ConstBatch<Base::kNu, W> u, float dt_s,
                        float* scratch, const float* ax, const float* ay, const float* yaw_accel) noexcept {
    if constexpr (HasBodyAccelHook<Base>) {
      base.template step_with_body_accel<W>(x, u, dt_s, scratch, ax, ay, yaw_accel);
    } else {
      base.template step<W>(x, u, dt_s, scratch);
      for (int j = 0; j < W; ++j) {
        x[state::kVx][j] += ax[j] * dt_s;
        if constexpr (kLateralVelocity) {
          x[state::kVy][j] += ay[j] * dt_s;
          x[state::kYawRate][j] += yaw_accel[j] * dt_s;
        }
      }
    }
  }

  static Base with_core(const Base& b, const EffectParams& e, double grip) {
    if constexpr (kChassisEffects) {
      auto p = b.params();
      single_track_core(p) = apply_effect_params(single_track_core(p), e, grip);
      std::string why;
      if (!single_track_core(p).is_valid(&why))
        throw Error("WithEffects: the effects make the model invalid: " + why);
      return Base(p);
    } else {
      for (const EffectSpec& spec : effect_table()) {
        if (spec.hook != EffectHook::kChassis) continue;
        for (const EffectParamSpec& q : spec.params)
          if (e.*(q.member) != EffectParams{}.*(q.member))
            throw Error("WithEffects: " + spec.id + " needs a chassis model (mass, tyres); this base model has none");
      }
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
  bool rolling_ = false;
  float front_roll_share_ = 0.5f, front_arm_m_ = 0, mass_per_yaw_inertia_ = 0, max_steer_rad_ = 0;
  bool grip_changes_ = false, patch_ = false, bump_ = false;
  float bump_x_ = 0, bump_y_ = 0, bump_r_ = 0, bump_slope_ = 0;
  struct Disc {
    float x_m, y_m, radius_m;
  };
  Disc discs_[1 + std::size(kOptionalPatchDiscs)] = {};  // the patch's discs (grip patch_grip_scale)
  int discs_n_ = 0;
  float gain_ = 1, offset_ = 0, steer_cubic_ = 0, left_gain_ = 1, right_gain_ = 1;  // steering map
  float throttle_gain_ = 1, thr_offset_ = 0, sag_ = 0;                              // throttle map
  bool esc_ = false;  // motor_freewheel, drag_brake
  bool speed_loop_ = false;
  float loop_top_speed_mps_ = 0, loop_gain_per_mps_ = 0, loop_integral_gain_per_m_ = 0, loop_feedforward_per_mps_ = 0;
  float freewheel_per_mps_ = 0, drag_brake_cmd_ = 0, brake_ratio_ = 1, inv_brake_ratio_ = 1, wheel_radius_ = 1;
  float front_drive_ = 0;  // the base's share of the drive on the front axle (after the effects)
  template <class List>
  struct TermsOf;
  template <class... E>
  struct TermsOf<TypeList<E...>> {
    using type = std::tuple<typename E::Term...>;
  };
  typename TermsOf<effects::DeclaredEffects>::type declared_;  // the declared effects' physics
};

using CorrectedSingleTrack = WithEffects<SingleTrack>;
using DoubleTrackWithEffects = WithEffects<DoubleTrack>;
using FullVehicleWithEffects = WithEffects<FullVehicle>;
using KinematicWithEffects = WithEffects<KinematicBicycle>;
using AutoRallyNetworkWithEffects = WithEffects<AutoRallyNetwork>;

}  // namespace mppi
