// The online grip adaptation's fit (mppi/lateral_force_adaptation.hpp) against the forgetting
// least-squares fit written out here term by term, its steady state in closed form, and the
// steps it must skip.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "mppi/lateral_force_adaptation.hpp"

namespace {
namespace st = mppi::state;
using State = std::array<float, st::kCommonStates>;

State state_of(float vx, float vy, float r) {
  State s{};
  s[st::kVx] = vx;
  s[st::kVy] = vy;
  s[st::kYawRate] = r;
  return s;
}

// One step's force parts as the fit defines them (measured with a trapezoid, predicted with the
// model's Euler term), written from the documented formulas.
struct ForceParts {
  double measured, model;
};
ForceParts parts(const State& x0, const State& pred, const State& x1, double dt, double scale_now) {
  const double kin0 = static_cast<double>(x0[st::kVx]) * x0[st::kYawRate];
  const double kin1 = static_cast<double>(x1[st::kVx]) * x1[st::kYawRate];
  return {static_cast<double>(x1[st::kVy]) - x0[st::kVy] + 0.5 * (kin0 + kin1) * dt,
          (static_cast<double>(pred[st::kVy]) - x0[st::kVy] + kin0 * dt) / scale_now};
}
}  // namespace

TEST_CASE("grip adaptation: the fit is forgetting least squares towards 1, term by term", "[mppi][adaptation]") {
  mppi::LateralForceAdaptation o;
  o.enabled = true;
  o.memory_s = 0.5f;
  o.min_scale = 0.2f;
  o.max_scale = 3.f;
  mppi::LateralForceScaleEstimator estimator(o);
  const double dt = 0.02, forget = std::exp(-dt / o.memory_s);
  std::mt19937 rng(11);
  auto uni = [&](double a, double b) { return static_cast<float>(std::uniform_real_distribution<double>(a, b)(rng)); };
  std::vector<ForceParts> history;
  float scale_now = 1.f;
  for (int step = 0; step < 200; ++step) {
    const State x0 = state_of(uni(3, 7), uni(-1, 1), uni(-1, 1));
    // a car with 0.6 of the model's lateral force, and noise
    const State pred = state_of(x0[st::kVx], x0[st::kVy] + uni(-0.15, 0.15), x0[st::kYawRate] + uni(-0.1, 0.1));
    const ForceParts p = parts(x0, pred, x0, dt, scale_now);
    const double kin0 = static_cast<double>(x0[st::kVx]) * x0[st::kYawRate];
    State x1 = state_of(x0[st::kVx], 0.f, x0[st::kYawRate]);
    // vy1 from m = 0.6 p + noise (vx, r kept, so the trapezoid's kinematic term is kin0 dt)
    x1[st::kVy] = static_cast<float>(x0[st::kVy] + 0.6 * p.model + uni(-0.01, 0.01) - kin0 * dt);
    history.push_back(parts(x0, pred, x1, dt, scale_now));
    const float got = estimator.update(x0.data(), pred.data(), x1.data(), static_cast<float>(dt), scale_now);
    double info = 0, cross = 0;  // the naive sums, newest weight 1
    for (std::size_t i = 0; i < history.size(); ++i) {
      const double w = std::pow(forget, static_cast<double>(history.size() - 1 - i));
      info += w * history[i].model * history[i].model;
      cross += w * history[i].model * history[i].measured;
    }
    const double expect = (cross + o.prior_weight) / (info + o.prior_weight);
    INFO("step " << step);
    REQUIRE(got == Approx(expect).epsilon(1e-4));
    // The model it asks next is at the new scale: its prediction's force part is that much larger.
    scale_now = got;
  }
  CHECK(scale_now == Approx(0.6).margin(0.05));
}

TEST_CASE("grip adaptation: steady cornering gives the closed form, within the bounds", "[mppi][adaptation]") {
  mppi::LateralForceAdaptation o;
  o.enabled = true;
  mppi::LateralForceScaleEstimator estimator(o);
  const double dt = 0.02, forget = std::exp(-dt / o.memory_s);
  // The model: the lateral velocity grows by 0.1 m/s per step beyond the kinematic term; the car: by 0.07.
  const State x0 = state_of(6.f, 0.f, 1.f);
  const double kin = 6.0 * 1.0 * dt;
  const State pred = state_of(6.f, static_cast<float>(0.1 - kin), 1.f);
  const State x1 = state_of(6.f, static_cast<float>(0.07 - kin), 1.f);
  float s = 1.f;
  for (int i = 0; i < 2000; ++i) s = estimator.update(x0.data(), pred.data(), x1.data(), static_cast<float>(dt), 1.f);
  const double info = 0.01 / (1 - forget);  // sum of 0.1^2 forget^i
  CHECK(s == Approx((0.7 * info + o.prior_weight) / (info + o.prior_weight)).epsilon(1e-4));
  CHECK(s == Approx(0.7).margin(0.01));

  // A car with a tenth of the model's force: the fit's lower bound.
  mppi::LateralForceScaleEstimator low(o);
  const State x1_low = state_of(6.f, static_cast<float>(0.01 - kin), 1.f);
  for (int i = 0; i < 2000; ++i) s = low.update(x0.data(), pred.data(), x1_low.data(), static_cast<float>(dt), 1.f);
  CHECK(s == o.min_scale);
}

TEST_CASE("grip adaptation: slow, impossible and non-finite steps tell nothing", "[mppi][adaptation]") {
  mppi::LateralForceAdaptation o;
  o.enabled = true;
  mppi::LateralForceScaleEstimator estimator(o);
  const float dt = 0.02f;
  // a first usable step: the fit with the prior
  const float first = estimator.update(state_of(5.f, 0.f, 0.f).data(), state_of(5.f, 0.2f, 0.f).data(),
                                       state_of(5.f, 0.1f, 0.f).data(), dt, 1.f);
  CHECK(first == Approx((0.2 * 0.1 + o.prior_weight) / (0.2 * 0.2 + o.prior_weight)).epsilon(1e-5));
  // below min_speed_mps; a put-back (3 m/s of lateral velocity gone in one step, 150 m/s^2); a
  // NaN: each returns the fitted scale as it was, whatever the model's scale
  CHECK(estimator.update(state_of(1.f, 0.f, 0.f).data(), state_of(1.f, 0.1f, 0.f).data(),
                         state_of(1.f, 0.05f, 0.f).data(), dt, 0.9f) == first);
  CHECK(estimator.update(state_of(5.f, 3.f, 0.f).data(), state_of(5.f, 3.1f, 0.f).data(), state_of(5.f, 0.f, 0.f).data(),
                         dt, 1.f) == first);
  const float nan = std::nanf("");
  CHECK(estimator.update(state_of(5.f, 0.f, 0.f).data(), state_of(5.f, nan, 0.f).data(), state_of(5.f, 0.f, 0.f).data(),
                         dt, 1.f) == first);
  CHECK(estimator.scale() == first);
  // none of them counted: the next usable step is the fit of the two usable ones
  const double forget = std::exp(-dt / o.memory_s);
  const float second = estimator.update(state_of(5.f, 0.f, 0.f).data(), state_of(5.f, 0.1f, 0.f).data(),
                                        state_of(5.f, 0.1f, 0.f).data(), dt, 1.f);
  const double info = forget * 0.04 + 0.01, cross = forget * 0.02 + 0.01;
  CHECK(second == Approx((cross + o.prior_weight) / (info + o.prior_weight)).epsilon(1e-5));
  estimator.clear();
  CHECK(estimator.scale() == 1.f);
}

TEST_CASE("grip adaptation: bad options are named", "[mppi][adaptation]") {
  mppi::LateralForceAdaptation o;
  std::string why;
  o.scale_model = true;
  CHECK_FALSE(o.is_valid(&why));
  CHECK_THAT(why, Catch::Contains("scale_model"));
  o.enabled = true;
  CHECK(o.is_valid(&why));
  o.memory_s = 0.f;
  CHECK_FALSE(o.is_valid(&why));
  CHECK_THAT(why, Catch::Contains("memory_s"));
  o.memory_s = 1.f;
  o.min_scale = 1.2f;
  CHECK_FALSE(o.is_valid(&why));
  CHECK_THAT(why, Catch::Contains("min_scale"));
  o.min_scale = 0.4f;
  o.speed_exponent = std::nanf("");
  CHECK_FALSE(o.is_valid(&why));
  CHECK_THAT(why, Catch::Contains("speed_exponent"));
}
