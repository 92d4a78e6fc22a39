// Adaptive temperature (mppi/adaptive_temperature.hpp): the effective sample size against its
// closed form for two cost levels, the solver against the target and its bounds, and a
// controller that holds the target in every step, on the fused CPU iteration and on the
// two-pass path.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "mppi/adaptive_temperature.hpp"
#include "mppi/controller.hpp"
#include "tests/mppi/linear_system.hpp"

using mppi::test::DoubleIntegrator;
using mppi::test::QuadraticCost;

TEST_CASE("effective sample size of two cost levels equals its closed form", "[core][mppi][temperature]") {
  // n0 samples at cost 0 and n1 at cost c: w = 1 and e = exp(-c / lambda),
  // ESS = (n0 + n1 e)^2 / (n0 + n1 e^2). A NaN weighs nothing.
  const int n0 = 3, n1 = 97;
  const double c = 2.0;
  std::vector<float> costs(n0, 5.f);
  costs.insert(costs.end(), n1, static_cast<float>(5.0 + c));
  costs.push_back(std::numeric_limits<float>::quiet_NaN());
  for (double lambda : {0.1, 1.0, 10.0}) {
    const double e = std::exp(-c / lambda);
    const double want = std::pow(n0 + n1 * e, 2) / (n0 + n1 * e * e);
    CHECK(mppi::effective_sample_size(costs, lambda) == Approx(want).epsilon(1e-6));
  }
  const std::vector<float> none(4, std::numeric_limits<float>::infinity());
  CHECK(mppi::effective_sample_size(none, 1.0) == 0.0);
}

TEST_CASE("the temperature solver meets the target, or stops at the bound it cannot pass",
          "[core][mppi][temperature]") {
  std::mt19937 rng(5);
  std::gamma_distribution<float> spread(2.f, 30.f);
  std::vector<float> costs(1920);
  for (float& s : costs) s = 100.f + spread(rng);
  mppi::TemperatureTarget target;
  target.tolerance = 0.05f;
  for (float share : {0.01f, 0.05f, 0.2f, 0.6f}) {
    target.ess_share = share;
    for (float start : {1e-3f, 6.f, 5e3f}) {
      double ess = 0;
      const float lambda = mppi::solve_temperature(costs, target, start, &ess);
      INFO("share " << share << " start " << start << " lambda " << lambda);
      CHECK(ess == Approx(mppi::effective_sample_size(costs, lambda)).epsilon(1e-5));  // lambda returned as float
      CHECK(std::abs(ess / (share * 1920.0) - 1) <= 0.05);
    }
  }
  // A target beyond reach: all costs equal but one far below -> ESS 1 at small lambda, and
  // the bound lambda_max = 1 cannot lift it to 50%.
  std::vector<float> one_best(100, 1000.f);
  one_best[7] = 0.f;
  target = {0.5f, 1e-3f, 1.f, 0.1f};
  double ess = 0;
  CHECK(mppi::solve_temperature(one_best, target, 0.5f, &ess) == Approx(1.f));
  CHECK(ess == Approx(1.0).margin(1e-9));
}

namespace {
mppi::ControllerOptions adaptive_options() {
  mppi::ControllerOptions o;
  o.num_samples = 512;
  o.horizon = 30;
  o.dt_s = 0.05f;
  o.lambda = 50.f;  // a poor first guess: the solver must move it by orders of magnitude
  o.noise_std = {1.f};
  o.control_min = {-10.f};
  o.control_max = {10.f};
  o.safe_control = {0.f};
  o.temperature.ess_share = 0.1f;
  o.temperature.tolerance = 0.1f;
  return o;
}

// Closed loop on the double integrator: every step's ESS within the tolerance of the target.
template <class MakeController>
void check_holds_target(MakeController&& make) {
  auto c = make(adaptive_options());
  float x[2] = {2.f, 0.f};
  const double want = 0.1 * 512;
  for (int step = 0; step < 60; ++step) {
    mppi::StepSummary s;
    const auto u = c.step(x, &s);
    REQUIRE(s.status == mppi::StepStatus::kOk);
    INFO("step " << step << " ESS " << s.effective_sample_size << " lambda " << s.lambda);
    CHECK(std::abs(s.effective_sample_size / want - 1) <= 0.1 + 1e-4);
    CHECK(s.lambda == Approx(c.temperature()).epsilon(0.5));  // the next step starts near it
    x[0] += 0.05f * x[1];
    x[1] += 0.05f * u[0];
  }
  CHECK(std::abs(x[0]) < 0.5f);  // and it still regulates
}

// A backend without iterate(): the controller's two-pass path (sample, roll out, weigh).
class DoubleIntegratorRollouts final : public mppi::Backend {
 public:
  DoubleIntegratorRollouts(int k, int t) : shape_{k, mppi::padded_sample_count(k), t, 2, 1} {}
  const char* name() const override { return "test"; }
  const mppi::RolloutShape& shape() const override { return shape_; }
  void rollout(std::span<const float> x0, std::span<const float> v, std::span<float> costs) override {
    const int p = shape_.padded_samples;
    for (int k = 0; k < p; ++k) {
      float pos = x0[0], vel = x0[1], s = 0;
      for (int t = 0; t < shape_.horizon; ++t) {
        const float u = v[static_cast<std::size_t>(t) * p + k];
        pos += 0.05f * vel;
        vel += 0.05f * u;
        s += pos * pos + 0.1f * vel * vel + 0.05f * u * u;
      }
      costs[k] = s;
    }
  }

 private:
  mppi::RolloutShape shape_;
};
}  // namespace

TEST_CASE("adaptive temperature holds the effective sample size in every step (fused CPU iteration)",
          "[core][mppi][temperature]") {
  check_holds_target([](const mppi::ControllerOptions& o) {
    return mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{1.f, 0.1f, 0.05f}, o);
  });
}

TEST_CASE("adaptive temperature holds the effective sample size in every step (two-pass path)",
          "[core][mppi][temperature]") {
  check_holds_target([](const mppi::ControllerOptions& o) {
    return mppi::Controller(std::make_unique<DoubleIntegratorRollouts>(o.num_samples, o.horizon), o);
  });
}

TEST_CASE("adaptive temperature settings out of range are refused", "[core][mppi][temperature]") {
  auto o = adaptive_options();
  std::string why;
  o.temperature.ess_share = 1.5f;
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("ess_share") != std::string::npos);
  o.temperature.ess_share = 0.1f;
  o.temperature.lambda_min = 0.f;
  CHECK_FALSE(o.is_valid(1, &why));
}
