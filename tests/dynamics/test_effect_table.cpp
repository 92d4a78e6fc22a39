// The effect table (dynamics/effects.hpp) and the one wrapper WithEffects<Model> over every
// model a corrected-model file can name. Oracles: the EffectParams struct itself (every member
// in the table once), the base models stepped alone, and the closed-form accelerations of the
// force effects (drag c v|v| / m, grade g * slope).
#include <catch2/catch.hpp>

#include <cmath>
#include <set>
#include <string>

#include "dynamics/corrected_model.hpp"
#include "dynamics/with_effects.hpp"
#include "mppi/error.hpp"
#include "mppi/type_list.hpp"
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
  if constexpr (M::kTyreEffects) {
    mass_kg = single_track_core(base.params()).mass_kg;
    g = single_track_core(base.params()).gravity_mps2;
  }
  float xb[Base::kNx], xw[M::kNx];
  std::vector<float> scratch(std::max<std::size_t>(1, base.scratch_floats(1)));
  start(base, xb, 8.f);
  start(wrapped, xw, 8.f);
  const float u[2] = {0.f, 0.f};
  const float dt_s = 0.002f;
  base.template step<1>(Batch<Base::kNx, 1>{xb}, ConstBatch<2, 1>{u}, dt_s, scratch.data());
  wrapped.template step<1>(Batch<M::kNx, 1>{xw}, ConstBatch<2, 1>{u}, dt_s, scratch.data());
  // Drag along body x, and the grade's downhill force split on the body axes (yaw 0.7 rad).
  const double yaw = 0.7;
  const double ax = -0.8 * 8.0 * 8.0 / mass_kg - g * 0.05 * std::cos(yaw);
  const double ay = g * 0.05 * std::sin(yaw);
  CHECK(xw[state::kVx] - xb[state::kVx] == Approx(ax * dt_s).epsilon(2e-3));
  if constexpr (M::kLateralVelocity) CHECK(xw[state::kVy] - xb[state::kVy] == Approx(ay * dt_s).epsilon(2e-3));
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
