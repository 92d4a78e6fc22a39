// The effect table (dynamics/effects.hpp) and the one wrapper WithEffects<Model> over every
// model a corrected-model file can name. Oracles: the EffectParams struct itself (every member
// in the table once), the base models stepped alone, and the closed-form accelerations of the
// force effects (drag c v|v| / m, grade g * slope).
#include <catch2/catch.hpp>

#include <cmath>
#include <set>
#include <string>

#include "base/error.hpp"
#include "base/type_list.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/with_effects.hpp"
#include "sim/data_dir.hpp"

using namespace mppi;

namespace {

template <class D>
typename D::Model default_base() {
  return corrected_nominal<D>(CorrectedModelFile{}, sim::network_file_or_default(""));
}

template <class M>
void start(const M& m, float* x, float vx_mps) {
  VehicleState s;
  s.vx_mps = vx_mps;
  s.yaw_rad = 0.7f;
  s.yaw_rate_radps = 0.2f;
  m.init_state(s, x);
}

// The base model and its corrected twin from the same start at vx_mps, one step of dt_s with
// command u each: xb and xw hold the states after it.
template <class B, class W>
void start_and_step_both(const B& base, const W& wrapped, float* xb, float* xw, float vx_mps, const float (&u)[2],
                         float dt_s) {
  std::vector<float> scratch(std::max<std::size_t>({1, base.scratch_floats(1), wrapped.scratch_floats(1)}));
  start(base, xb, vx_mps);
  start(wrapped, xw, vx_mps);
  base.template step<1>(Batch<B::kNx, 1>{xb}, ConstBatch<2, 1>{u}, dt_s, scratch.data());
  wrapped.template step<1>(Batch<W::kNx, 1>{xw}, ConstBatch<2, 1>{u}, dt_s, scratch.data());
}

}  // namespace

TEST_CASE("the effect table holds every effect parameter exactly once", "[effects]") {
  static_assert(sizeof(EffectParams) % sizeof(double) == 0);
  std::set<std::string> ids, keys;
  EffectParams probe;
  std::size_t params = 0;
  for (const EffectSpec& spec : effect_table()) {
    CHECK(ids.insert(spec.id).second);
    for (const EffectParamSpec& p : spec.params) {
      CHECK(keys.insert(p.name).second);
      ++params;
      // The default is inside the fit range and valid; the fit range lies inside the valid range.
      CHECK(probe.*(p.member) >= p.lo);
      CHECK(probe.*(p.member) <= p.hi);
      probe.*(p.member) += 12345.0;  // marks the member as covered
    }
  }
  CHECK(params == sizeof(EffectParams) / sizeof(double));
  const EffectParams defaults;
  const auto* marked = reinterpret_cast<const double*>(&probe);
  const auto* plain = reinterpret_cast<const double*>(&defaults);
  for (std::size_t i = 0; i < params; ++i) CHECK(marked[i] != plain[i]);
}

TEST_CASE("effect parameters are validated from the table with the key named", "[effects]") {
  EffectParams e;
  std::string why;
  CHECK(e.is_valid(&why));
  e.steer_delay_s = -0.1;
  CHECK_FALSE(e.is_valid(&why));
  CHECK(why.find("steer_delay_s") != std::string::npos);
  e = {};
  e.grade_y = 0.6;
  CHECK_FALSE(e.is_valid(&why));
  CHECK(why.find("grade_y") != std::string::npos);
  e = {};
  e.aero_drag_kgpm = std::nan("");
  CHECK_FALSE(e.is_valid(&why));
  e = {};  // a bump needs an extent
  e.bump_height_m = 0.4;
  CHECK_FALSE(e.is_valid(&why));
  CHECK(why.find("bump_radius_m") != std::string::npos);
  e.bump_radius_m = 5.0;
  CHECK(e.is_valid(&why));
  CHECK_THROWS_WITH(corrected_model_from_yaml("effects:\n  bump_height_m: 0.4\n", "bump.yaml"),
                    Catch::Contains("bump.yaml") && Catch::Contains("bump_radius_m"));
  CHECK_THROWS_WITH(corrected_model_from_yaml("effects:\n  voltage_sag: 1.5\n", "sag.yaml"),
                    Catch::Contains("sag.yaml:2") && Catch::Contains("voltage_sag"));
}

TEMPLATE_LIST_TEST_CASE("WithEffects<Model> with no effects steps exactly like the model", "[effects]",
                        CorrectedNominalModels) {
  using D = TestType;
  using Base = typename D::Model;
  using M = WithEffects<Base>;
  const Base base = default_base<D>();
  const M wrapped(base);
  float xb[Base::kNx], xw[M::kNx];
  std::vector<float> scratch(std::max<std::size_t>(1, base.scratch_floats(1)));
  start(base, xb, 5.f);
  start(wrapped, xw, 5.f);
  for (int k = 0; k < 200; ++k) {
    const float u[2] = {0.4f * std::sin(0.02f * k), 0.5f};
    base.template step<1>(Batch<Base::kNx, 1>{xb}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
    wrapped.template step<1>(Batch<M::kNx, 1>{xw}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
  }
  for (int i = 0; i < Base::kNx; ++i) CHECK(xw[i] == xb[i]);
  CHECK(xw[M::kTime] == Approx(0.4).margin(1e-4));
}

TEMPLATE_LIST_TEST_CASE("force effects add their closed-form acceleration in one step", "[effects]",
                        CorrectedNominalModels) {
  using D = TestType;
  using Base = typename D::Model;
  using M = WithEffects<Base>;
  EffectParams e;
  e.aero_drag_kgpm = 0.8;
  e.grade_x = 0.05;
  const Base base = default_base<D>();
  const M wrapped(base, e);
  double mass_kg = SingleTrackParams{}.mass_kg, g = SingleTrackParams{}.gravity_mps2;
  if constexpr (M::kChassisEffects) {
    mass_kg = single_track_core(base.params()).mass_kg;
    g = single_track_core(base.params()).gravity_mps2;
  }
  float xb[Base::kNx], xw[M::kNx];
  const float u[2] = {0.f, 0.f};
  const float dt_s = 0.002f;
  start_and_step_both(base, wrapped, xb, xw, 8.f, u, dt_s);
  // Drag along body x, and the grade's downhill force split on the body axes (yaw 0.7 rad).
  const double yaw = 0.7;
  const double ax = -0.8 * 8.0 * 8.0 / mass_kg - g * 0.05 * std::cos(yaw);
  const double ay = g * 0.05 * std::sin(yaw);
  CHECK(xw[state::kVx] - xb[state::kVx] == Approx(ax * dt_s).epsilon(2e-3));
  if constexpr (M::kLateralVelocity) CHECK(xw[state::kVy] - xb[state::kVy] == Approx(ay * dt_s).epsilon(2e-3));
}

TEMPLATE_LIST_TEST_CASE("rolling resistance acts along each wheel: steered, it also pushes sideways and turns the nose back",
                        "[effects]", CorrectedNominalModels) {
  using D = TestType;
  using Base = typename D::Model;
  using M = WithEffects<Base>;
  EffectParams e;
  e.rolling_force_N = 15.0;
  e.rolling_viscous_Nspm = 2.0;
  const Base base = default_base<D>();
  const M wrapped(base, e);
  SingleTrackParams car;  // the geometry: the base's own where it has a single-track core
  if constexpr (M::kChassisEffects) car = single_track_core(base.params());
  const double m = car.mass_kg, lf = car.cg_to_front_axle_m, lr = car.cg_to_rear_axle_m;
  float xb[Base::kNx], xw[M::kNx];
  for (const float steer : {0.f, 0.5f, -0.8f}) {
    const float u[2] = {steer, 0.f};
    const float dt_s = 0.002f;
    start_and_step_both(base, wrapped, xb, xw, 8.f, u, dt_s);  // v_x 8 m/s, v_y 0, yaw rate 0.2 rad/s
    // Each axle's share of the static load takes F(v) = F0 tanh(2 v) + b v against its own rolling
    // speed, along its wheel; the front wheel is turned by delta = steer x max steer.
    const double delta = steer * car.max_steer_rad, vx = 8.0, r = 0.2;
    const double front_speed = vx * std::cos(delta) + lf * r * std::sin(delta);
    auto force = [](double v) { return 15.0 * std::tanh(2.0 * v) + 2.0 * v; };
    const double front_N = lr / (lf + lr) * force(front_speed), rear_N = lf / (lf + lr) * force(vx);
    const double ax = -(front_N * std::cos(delta) + rear_N) / m;
    const double ay = -front_N * std::sin(delta) / m;
    const double yaw_accel = -lf * front_N * std::sin(delta) / car.yaw_inertia_kgm2;
    INFO("steer " << steer);
    CHECK(xw[state::kVx] - xb[state::kVx] == Approx(ax * dt_s).epsilon(3e-3));
    if constexpr (M::kLateralVelocity) {
      CHECK(xw[state::kVy] - xb[state::kVy] == Approx(ay * dt_s).epsilon(3e-3).margin(1e-7));
      CHECK(xw[state::kYawRate] - xb[state::kYawRate] == Approx(yaw_accel * dt_s).epsilon(3e-3).margin(1e-7));
    }
  }
}

TEST_CASE("tyre effects are refused where the model has no tyres, with the effect named", "[effects]") {
  EffectParams e;
  e.tyre_peak_scale = 0.8;
  CHECK_THROWS_WITH(KinematicWithEffects(KinematicBicycle(), e), Catch::Contains("tire_saturation"));
  e = {};
  e.cg_height_delta_m = 0.05;
  CHECK_THROWS_WITH(KinematicWithEffects(KinematicBicycle(), e), Catch::Contains("load_transfer"));
  CHECK_NOTHROW(CorrectedSingleTrack(SingleTrack(), e));
}

namespace {

// The applied (last-stage) output of the steer and throttle chains.
template <class M>
float applied_steer_stage(const float* x) { return x[M::kSteerChain + M::kChain - 1]; }
template <class M>
float applied_throttle_stage(const float* x) { return x[M::kThrottleChain + M::kChain - 1]; }

// Steps base and wrapped model side by side from the same start; the wrapped one gets command
// u, the base one command u_base. Returns the largest state difference.
float max_difference_after(const SingleTrack& base, const CorrectedSingleTrack& wrapped, const float u[2],
                           const float u_base[2], int steps) {
  float xb[SingleTrack::kNx], xw[CorrectedSingleTrack::kNx];
  std::vector<float> scratch(std::max<std::size_t>(1, base.scratch_floats(1)));
  start(base, xb, 4.f);
  start(wrapped, xw, 4.f);
  wrapped.set_actuators(xw, u[0], u[1]);
  float worst = 0;
  for (int k = 0; k < steps; ++k) {
    base.step<1>(Batch<SingleTrack::kNx, 1>{xb}, ConstBatch<2, 1>{u_base}, 0.002f, scratch.data());
    wrapped.step<1>(Batch<CorrectedSingleTrack::kNx, 1>{xw}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
  }
  for (int i = 0; i < SingleTrack::kNx; ++i) worst = std::max(worst, std::abs(xw[i] - xb[i]));
  return worst;
}

}  // namespace

TEST_CASE("a rate limit moves the applied command at most r per second", "[effects]") {
  EffectParams e;
  e.steer_slew_s = 0.5;     // 2 per second
  e.throttle_slew_s = 2.0;  // 0.5 per second
  using M = CorrectedSingleTrack;
  const M m(SingleTrack(), e);
  float x[M::kNx] = {};
  m.set_actuators(x, 0.f, 0.f);
  const float dt_s = 0.01f;
  for (int k = 1; k <= 80; ++k) {
    m.advance_actuators(x, 1.f, 1.f, dt_s);  // a step from 0 to 1 at t = 0
    const double t = k * dt_s;
    CHECK(applied_steer_stage<M>(x) == Approx(std::min(1.0, 2.0 * t)).margin(1e-5));
    CHECK(applied_throttle_stage<M>(x) == Approx(std::min(1.0, 0.5 * t)).margin(1e-5));
  }
}

TEST_CASE("steering backlash is a play operator of the given width", "[effects]") {
  EffectParams e;
  e.steer_backlash = 0.1;  // half width h = 0.05
  using M = CorrectedSingleTrack;
  const M m(SingleTrack(), e);
  float x[M::kNx] = {};
  m.set_actuators(x, 0.f, 0.f);
  // Up from 0 to 0.5: the wheels trail the servo by h. Down again: they stay at 0.45 until the
  // servo has crossed the play (0.5 -> 0.4), then trail by h on the other side.
  double in = 0.0;
  for (int k = 1; k <= 50; ++k) {
    in = 0.01 * k;
    m.advance_actuators(x, static_cast<float>(in), 0.f, 0.01f);
    CHECK(applied_steer_stage<M>(x) == Approx(std::max(0.0, in - 0.05)).margin(1e-5));
  }
  for (int k = 1; k <= 50; ++k) {
    in = 0.5 - 0.01 * k;
    m.advance_actuators(x, static_cast<float>(in), 0.f, 0.01f);
    const double expected = in > 0.4 ? 0.45 : in + 0.05;
    CHECK(applied_steer_stage<M>(x) == Approx(expected).margin(1e-5));
  }
}

TEST_CASE("command maps equal the base model driven with the mapped command", "[effects]") {
  const SingleTrack base;
  const float u[2] = {0.3f, 0.6f};
  SECTION("cubic steering") {
    EffectParams e;
    e.steer_cubic = 0.5;
    const float ub[2] = {0.3f + 0.5f * 0.027f, 0.6f};
    CHECK(max_difference_after(base, CorrectedSingleTrack(base, e), u, ub, 300) < 1e-4f);
  }
  SECTION("asymmetric steering, left and right") {
    EffectParams e;
    e.steer_asymmetry = 0.2;
    const float ub_left[2] = {0.36f, 0.6f};
    CHECK(max_difference_after(base, CorrectedSingleTrack(base, e), u, ub_left, 300) < 1e-4f);
    const float u_right[2] = {-0.3f, 0.6f}, ub_right[2] = {-0.24f, 0.6f};
    CHECK(max_difference_after(base, CorrectedSingleTrack(base, e), u_right, ub_right, 300) < 1e-4f);
  }
  SECTION("throttle gain") {
    EffectParams e;
    e.throttle_gain = 1.5;
    const float ub[2] = {0.3f, 0.9f};
    CHECK(max_difference_after(base, CorrectedSingleTrack(base, e), u, ub, 300) < 1e-4f);
    // and the map is really applied: the unmapped command differs.
    CHECK(max_difference_after(base, CorrectedSingleTrack(base, e), u, u, 300) > 1e-2f);
  }
}

TEST_CASE("payload and motor speed equal the base model with its mass, inertia and motor changed", "[effects]") {
  EffectParams e;
  e.mass_scale = 1.25;
  e.yaw_inertia_scale = 1.4;
  e.motor_speed_scale = 0.8;
  SingleTrackParams heavy;
  heavy.mass_kg *= 1.25;
  heavy.yaw_inertia_kgm2 *= 1.4;
  heavy.no_load_speed_mps *= 0.8;
  const float u[2] = {0.25f, 0.7f};
  CHECK(max_difference_after(SingleTrack(heavy), CorrectedSingleTrack(SingleTrack(), e), u, u, 500) < 1e-5f);
  CHECK(max_difference_after(SingleTrack(), CorrectedSingleTrack(SingleTrack(), e), u, u, 500) > 1e-2f);
}

TEST_CASE("a weight distribution is the base model with its CG moved along the wheelbase", "[effects]") {
  const SingleTrackParams nominal;
  const double wheelbase_m = nominal.cg_to_front_axle_m + nominal.cg_to_rear_axle_m;
  const float u[2] = {0.3f, 0.5f};
  for (const double s : {0.1, -0.05}) {
    INFO("shift " << s);
    EffectParams e;
    e.cg_shift_rear = s;
    SingleTrackParams moved = nominal;  // the oracle: the CG s L further back, the wheelbase kept
    moved.cg_to_front_axle_m = nominal.cg_to_front_axle_m + s * wheelbase_m;
    moved.cg_to_rear_axle_m = nominal.cg_to_rear_axle_m - s * wheelbase_m;
    CHECK(max_difference_after(SingleTrack(moved), CorrectedSingleTrack(SingleTrack(), e), u, u, 500) < 1e-5f);
    CHECK(max_difference_after(SingleTrack(), CorrectedSingleTrack(SingleTrack(), e), u, u, 500) > 1e-2f);
  }
  // Beyond an axle the car is not a car: refused with the reason.
  EffectParams beyond;
  beyond.cg_shift_rear = 0.9;
  CHECK_THROWS_WITH(CorrectedSingleTrack(SingleTrack(), beyond), Catch::Contains("cg_to_rear_axle_m"));
}

TEST_CASE("a drive split is the base model with that share of the motor torque on the front axle", "[effects]") {
  const float u[2] = {0.2f, 0.8f};
  EffectParams e;
  e.front_drive_shift = 0.4;
  SingleTrackParams four_wheel;
  four_wheel.front_drive_share = 0.4;
  CHECK(max_difference_after(SingleTrack(four_wheel), CorrectedSingleTrack(SingleTrack(), e), u, u, 500) < 1e-5f);
  CHECK(max_difference_after(SingleTrack(), CorrectedSingleTrack(SingleTrack(), e), u, u, 500) > 1e-2f);
  // The share stays within [0, 1]: a shift past it is the whole torque on one axle.
  e.front_drive_shift = 1.0;
  four_wheel.front_drive_share = 0.6;
  SingleTrackParams front_only;
  front_only.front_drive_share = 1.0;
  CHECK(max_difference_after(SingleTrack(front_only), CorrectedSingleTrack(SingleTrack(four_wheel), e), u, u, 500) < 1e-5f);
  // The double-track model drives its rear axle only: refused with the reason.
  EffectParams split;
  split.front_drive_shift = 0.3;
  CHECK_THROWS_WITH(DoubleTrackWithEffects(DoubleTrack(), split), Catch::Contains("front_drive_share"));
}

TEST_CASE("a grip patch is the base model with the friction curve scaled on the patch only", "[effects]") {
  SingleTrackParams slippery;  // the friction curve (peak and vertical shift) x 0.5
  slippery.tyre.D *= 0.5;
  slippery.tyre.Sv *= 0.5;
  const float u[2] = {0.3f, 0.6f};
  EffectParams far_away;  // a patch the car never reaches
  far_away.patch_x_m = 100;
  far_away.patch_y_m = 100;
  far_away.patch_radius_m = 3;
  far_away.patch_grip_scale = 0.5;
  CHECK(max_difference_after(SingleTrack(), CorrectedSingleTrack(SingleTrack(), far_away), u, u, 500) == 0.f);
  EffectParams around = far_away;  // a patch the car never leaves
  around.patch_x_m = 0;
  around.patch_y_m = 0;
  around.patch_radius_m = 50;
  CHECK(max_difference_after(SingleTrack(slippery), CorrectedSingleTrack(SingleTrack(), around), u, u, 500) < 1e-5f);
  CHECK(max_difference_after(SingleTrack(), CorrectedSingleTrack(SingleTrack(), around), u, u, 500) > 1e-2f);
  // A second or third disc of the same surface acts like the first: the car inside any one of
  // them has the slippery curve, whatever the others are; radius 0 is no disc.
  EffectParams second = far_away;
  second.patch2_radius_m = 50;
  CHECK(max_difference_after(SingleTrack(slippery), CorrectedSingleTrack(SingleTrack(), second), u, u, 500) < 1e-5f);
  EffectParams third = far_away;
  third.patch2_x_m = -100;
  third.patch2_radius_m = 3;
  third.patch3_radius_m = 50;
  CHECK(max_difference_after(SingleTrack(slippery), CorrectedSingleTrack(SingleTrack(), third), u, u, 500) < 1e-5f);
  EffectParams none_there = third;
  none_there.patch3_radius_m = 0;
  CHECK(max_difference_after(SingleTrack(), CorrectedSingleTrack(SingleTrack(), none_there), u, u, 500) == 0.f);

  // On the patch's edge (distance = radius) the step is the mean of the two grips' steps.
  EffectParams edge = far_away;
  edge.patch_x_m = 2;
  edge.patch_y_m = 0;
  edge.patch_radius_m = 2;
  const CorrectedSingleTrack wrapped(SingleTrack(), edge);
  float xw[CorrectedSingleTrack::kNx], xn[SingleTrack::kNx], xs[SingleTrack::kNx];
  std::vector<float> scratch(std::max<std::size_t>(1, wrapped.scratch_floats(1)));
  start(wrapped, xw, 5.f);
  wrapped.set_actuators(xw, u[0], u[1]);
  start(SingleTrack(), xn, 5.f);
  start(SingleTrack(), xs, 5.f);
  for (int i = 0; i < 3; ++i) {  // a few steps of turning first, so that the grip matters
    SingleTrack().step<1>(Batch<SingleTrack::kNx, 1>{xn}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
  }
  std::copy(xn, xn + SingleTrack::kNx, xs);
  std::copy(xn, xn + SingleTrack::kNx, xw);
  xw[state::kX] = xs[state::kX] = xn[state::kX] = 0.f;
  xw[state::kY] = xs[state::kY] = xn[state::kY] = 0.f;
  SingleTrack().step<1>(Batch<SingleTrack::kNx, 1>{xn}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
  SingleTrack(slippery).step<1>(Batch<SingleTrack::kNx, 1>{xs}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
  wrapped.step<1>(Batch<CorrectedSingleTrack::kNx, 1>{xw}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
  for (int i = 0; i < SingleTrack::kNx; ++i) CHECK(xw[i] == Approx(0.5f * (xn[i] + xs[i])).margin(1e-6));
  CHECK(std::abs(xn[state::kVy] - xs[state::kVy]) + std::abs(xn[state::kYawRate] - xs[state::kYawRate]) > 1e-5f);

  EffectParams both = far_away;  // one other grip at a time
  both.grip_scale = 0.8;
  CHECK_THROWS_WITH(CorrectedSingleTrack(SingleTrack(), both), Catch::Contains("cannot be combined"));
}

namespace {

// v_x [m/s] after driving straight for `seconds` at throttle u from speed v0 (wheels rolling),
// the actuator chains settled on u.
template <class M>
double speed_after(const M& m, float v0_mps, float u_throttle, double seconds) {
  std::vector<float> x(M::kNx, 0.f);
  VehicleState s;
  s.vx_mps = v0_mps;
  m.init_state(s, x.data());
  if constexpr (requires { M::set_actuators(x.data(), 0.f, 0.f); }) m.set_actuators(x.data(), 0.f, u_throttle);
  const float u[2] = {0.f, u_throttle};
  const float dt = 0.002f;
  for (int i = 0; i < static_cast<int>(seconds / dt + 0.5); ++i)
    m.template step<1>(Batch<M::kNx, 1>{x.data()}, ConstBatch<2, 1>{u}, dt, nullptr);
  return x[state::kVx];
}

}  // namespace

TEST_CASE("a freewheeling motor takes the share f (1 - |u|) of the back-EMF braking away", "[effects]") {
  // Nominal drive torque T_stall (u - omega R / v_nl); with the share f of the back-EMF braking
  // acting only while the PWM is on, T_stall (u - omega R / v_nl ((1 - f) + f |u|)) (f = 1:
  // Liniger et al.'s (a - b v) u, the law of the DART and ETH RC cars). At a fixed command that is
  // the base model with the no-load speed v_nl / ((1 - f) + f |u|) (oracle).
  SingleTrackParams p;
  p.stall_torque_Nm = 0.82;
  p.wheel_radius_m = 0.0325;
  p.no_load_speed_mps = 5.27;
  p.mass_kg = 1.58;
  p.yaw_inertia_kgm2 = 0.0048;
  p.brake_torque_ratio = 0.5;
  for (const double f : {1.0, 0.4}) {
    EffectParams e;
    e.motor_freewheel_share = f;
    const CorrectedSingleTrack freewheel{SingleTrack(p), e};
    for (const float v : {1.5f, 3.0f}) {
      for (const float u : {0.0f, 0.3f, -0.5f, 1.0f, 1.3f}) {
        INFO("f " << f << ", v " << v << " m/s, u " << u);
        const double duty = std::min(std::abs(static_cast<double>(u)), 1.0);
        SingleTrackParams motor = p;
        motor.no_load_speed_mps = (1 - f) + f * duty > 0 ? p.no_load_speed_mps / ((1 - f) + f * duty) : 1e7;
        const double expected = speed_after(SingleTrack(motor), v, u, 0.5);
        CHECK(speed_after(freewheel, v, u, 0.5) == Approx(expected).margin(2e-3));
        if (duty < 1.0) CHECK(std::abs(expected - speed_after(SingleTrack(p), v, u, 0.5)) > 0.005);  // it matters
      }
    }
  }
  // With a payload the motor drives the heavier car.
  EffectParams heavy;
  heavy.motor_freewheel_share = 1.0;
  heavy.mass_scale = 2.0;
  SingleTrackParams heavy_motor = p;
  heavy_motor.mass_kg *= 2.0;
  heavy_motor.no_load_speed_mps = 1e7;  // no back-EMF braking at neutral
  CHECK(speed_after(CorrectedSingleTrack{SingleTrack(p), heavy}, 2.f, 0.f, 0.5) ==
        Approx(speed_after(SingleTrack(heavy_motor), 2.f, 0.f, 0.5)).margin(2e-3));
  // Refused where the base has no motor of its own.
  EffectParams full;
  full.motor_freewheel_share = 1.0;
  CHECK_THROWS_AS(KinematicWithEffects(KinematicBicycle(), full), Error);
}

TEST_CASE("a drag brake decelerates the car by a_db at neutral command, and only there", "[effects]") {
  SingleTrackParams p;  // the AutoRally car, without the resistances the closed forms leave out
  p.rolling_resistance = 0.0;
  p.aero_drag_kgpm = 0.0;
  p.brake_torque_ratio = 0.4;
  SingleTrackParams no_emf = p;  // a motor without back-EMF: coasting keeps the speed
  no_emf.no_load_speed_mps = 1e7;
  // The brake torque m R a_db decelerates the car and its wheels (m_eff = m + (I_f + I_r) / R^2)
  // by a_db m / m_eff: a straight line while v >> 0.5 m/s (within 4 %: the tyres slip while they
  // brake, which the closed form leaves out).
  const double m_eff = p.mass_kg + (p.front_wheel_inertia_kgm2 + p.rear_wheel_inertia_kgm2) / (p.wheel_radius_m * p.wheel_radius_m);
  const double drop_mps = 2.0 * p.mass_kg / m_eff;  // a_db = 2 m/s^2 for 1 s
  EffectParams brake;
  brake.drag_brake_mps2 = 2.0;
  const CorrectedSingleTrack braked{SingleTrack(no_emf), brake};
  const CorrectedSingleTrack plain{SingleTrack(no_emf)};
  CHECK(5.0 - speed_after(plain, 5.f, 0.f, 1.0) == Approx(0.0).margin(0.01));
  CHECK(5.0 - speed_after(braked, 5.f, 0.f, 1.0) == Approx(drop_mps).epsilon(0.04));
  // Within 0.05 of neutral the whole brake acts, on top of the drive; halfway through the band's
  // edge (|u| 0.05 -> 0.1) half of it; beyond it none.
  CHECK(speed_after(plain, 5.f, 0.03f, 1.0) - speed_after(braked, 5.f, 0.03f, 1.0) == Approx(drop_mps).epsilon(0.04));
  CHECK(speed_after(plain, 5.f, 0.075f, 1.0) - speed_after(braked, 5.f, 0.075f, 1.0) ==
        Approx(0.5 * drop_mps).epsilon(0.04));
  CHECK(speed_after(braked, 5.f, 0.3f, 1.0) == Approx(speed_after(plain, 5.f, 0.3f, 1.0)).margin(1e-4));
  CHECK(speed_after(braked, 5.f, -0.3f, 1.0) == Approx(speed_after(plain, 5.f, -0.3f, 1.0)).margin(1e-4));
  // Reversing, it brakes the other way.
  CHECK(speed_after(braked, -4.f, 0.f, 1.0) + 4.0 == Approx(drop_mps).epsilon(0.04));
  // With the motor freewheeling at neutral (motor_freewheel f = 1: no back-EMF braking there) the
  // drag brake is all that slows the coasting car: a PWM ESC's neutral in drive-brake mode.
  // A 1:10 RC car (data/config/eth_rccar_single_track.yaml, with a weaker motor, so its back-EMF
  // braking stays within the rear tyre's grip and the closed form holds), whose wheels are light.
  SingleTrackParams rc = p;
  rc.mass_kg = 1.65;
  rc.yaw_inertia_kgm2 = 0.0155;
  rc.cg_to_front_axle_m = 0.13;
  rc.cg_to_rear_axle_m = 0.17;
  rc.cg_height_m = 0.03;
  rc.wheel_radius_m = 0.0325;
  rc.front_wheel_inertia_kgm2 = rc.rear_wheel_inertia_kgm2 = 5e-5;
  rc.stall_torque_Nm = 0.3;
  rc.no_load_speed_mps = 6.0;
  const double rc_drop_mps = 1.0 * 0.5 * rc.mass_kg / (rc.mass_kg + 2 * 5e-5 / (0.0325 * 0.0325));  // 0.5 s
  EffectParams esc;
  esc.drag_brake_mps2 = 1.0;
  esc.motor_freewheel_share = 1.0;
  CHECK(2.5 - speed_after(CorrectedSingleTrack{SingleTrack(rc), esc}, 2.5f, 0.f, 0.5) == Approx(rc_drop_mps).epsilon(0.06));
  CHECK(2.5 - speed_after(CorrectedSingleTrack{SingleTrack(rc)}, 2.5f, 0.f, 0.5) > 1.5 * rc_drop_mps);  // back-EMF
  // Refused where the base has no motor of its own; a negative brake refused by name.
  CHECK_THROWS_AS(KinematicWithEffects(KinematicBicycle(), brake), Error);
  EffectParams bad;
  bad.drag_brake_mps2 = -1.0;
  CHECK_THROWS_WITH(CorrectedSingleTrack(SingleTrack(p), bad), Catch::Contains("drag_brake_mps2"));
}

namespace {

// The driven (rear) wheels' rim speed [m/s] after driving straight for `seconds` at command u
// from 2 m/s.
double rim_speed_after(const CorrectedSingleTrack& m, const SingleTrackParams& car, float u, double seconds) {
  std::vector<float> x(CorrectedSingleTrack::kNx, 0.f);
  VehicleState s;
  s.vx_mps = 2.f;
  m.init_state(s, x.data());
  const float cmd[2] = {0.f, u};
  for (int i = 0; i < static_cast<int>(seconds / 0.002 + 0.5); ++i)
    m.step<1>(Batch<CorrectedSingleTrack::kNx, 1>{x.data()}, ConstBatch<2, 1>{cmd}, 0.002f, nullptr);
  return x[SingleTrack::kOmegaRear] * car.wheel_radius_m;
}

}  // namespace

TEST_CASE("a speed loop sets the throttle V u / v_nl + k e + k_i int e and holds the speed V u", "[effects]") {
  SingleTrackParams p;  // the AutoRally car, without the resistances the closed form leaves out
  p.rolling_resistance = 0.0;
  p.aero_drag_kgpm = 0.0;
  EffectParams e;
  e.speed_loop_top_speed_mps = 10.0;
  e.speed_loop_gain = 0.3;
  const SingleTrack base(p);
  const CorrectedSingleTrack loop(base, e);
  SECTION("one step: the base model driven with the loop's throttle from the rim speed") {
    for (const float v : {2.f, 5.f, 8.f}) {
      for (const float u : {0.1f, 0.5f, -0.2f, 0.95f}) {
        INFO("v " << v << " m/s, speed command " << u);
        float xb[SingleTrack::kNx], xw[CorrectedSingleTrack::kNx];
        start(base, xb, v);
        start(loop, xw, v);
        loop.set_actuators(xw, 0.f, u);
        const float rim_mps = xb[SingleTrack::kOmegaRear] * static_cast<float>(p.wheel_radius_m);
        const double target_mps = 10.0 * u;
        const float throttle = static_cast<float>(
            std::clamp(target_mps / p.no_load_speed_mps + 0.3 * (target_mps - rim_mps), -1.0, 1.0));
        const float ub[2] = {0.f, throttle}, uw[2] = {0.f, u};
        base.step<1>(Batch<SingleTrack::kNx, 1>{xb}, ConstBatch<2, 1>{ub}, 0.002f, nullptr);
        loop.step<1>(Batch<CorrectedSingleTrack::kNx, 1>{xw}, ConstBatch<2, 1>{uw}, 0.002f, nullptr);
        for (int i = 0; i < SingleTrack::kNx; ++i) CHECK(xw[i] == Approx(xb[i]).margin(1e-5));
      }
    }
  }
  SECTION("steady state: without resistances the DC-motor line's torque vanishes at v = V u") {
    // T = T_stall (V u / v_nl + k (V u - v) - v / v_nl) = T_stall (1 / v_nl + k) (V u - v)
    for (const float u : {0.3f, 0.6f}) {
      CHECK(speed_after(loop, 2.f, u, 8.0) == Approx(10.0 * u).margin(0.02));
      CHECK(std::abs(speed_after(base, 2.f, u, 8.0) - 10.0 * u) > 1.0);  // the bare command is a throttle
    }
  }
  SECTION("with the car's resistances, the integral takes the steady-state error away") {
    // Rolling resistance and drag need a throttle beyond the feedforward: a proportional loop
    // settles where k e pays for them (e > 0); with k_i > 0 it settles only where e = 0. The loop
    // measures the driven wheels' rim speed, which the tyre's drive slip keeps above v_x.
    const SingleTrackParams car;
    EffectParams pi = e;
    pi.speed_loop_integral_gain = 1.5;
    const float u = 0.5f;
    CHECK(rim_speed_after(CorrectedSingleTrack(SingleTrack(car), pi), car, u, 25.0) == Approx(10.0 * u).margin(0.02));
    CHECK(10.0 * u - rim_speed_after(CorrectedSingleTrack(SingleTrack(car), e), car, u, 25.0) > 0.1);
  }
  SECTION("the integral holds while the throttle is at its limit (anti-windup)") {
    // From rest a command of 0.9 asks for 9 m/s: the throttle saturates at 1 and the integral
    // must not grow meanwhile, or the speed would overshoot V u by far.
    EffectParams pi = e;
    pi.speed_loop_integral_gain = 3.0;
    const SingleTrackParams car;
    const CorrectedSingleTrack m(SingleTrack(car), pi);
    std::vector<float> x(CorrectedSingleTrack::kNx, 0.f);
    VehicleState s;
    s.vx_mps = 0.5f;
    m.init_state(s, x.data());
    const float cmd[2] = {0.f, 0.9f};
    auto rim_mps = [&] { return x[SingleTrack::kOmegaRear] * static_cast<float>(car.wheel_radius_m); };
    float top_mps = 0;
    for (int i = 0; i < 10000; ++i) {
      m.step<1>(Batch<CorrectedSingleTrack::kNx, 1>{x.data()}, ConstBatch<2, 1>{cmd}, 0.002f, nullptr);
      top_mps = std::max(top_mps, rim_mps());
    }
    CHECK(top_mps < 9.0 + 0.3);
    CHECK(rim_mps() == Approx(9.0).margin(0.03));
  }
  SECTION("off at its default: a top speed of 0") {
    const float u[2] = {0.2f, 0.4f};
    EffectParams off;
    off.speed_loop_gain = 2.0;
    CHECK(max_difference_after(SingleTrack(), CorrectedSingleTrack(SingleTrack(), off), u, u, 300) < 1e-6f);
  }
}
