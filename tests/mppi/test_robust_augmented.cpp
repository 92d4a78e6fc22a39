// Robust MPPI's augmented sampling (ControllerOptions::robust_augmented_sampling; AugmentedSampling
// in mppi/backend.hpp): each sample is also rolled out as the real system, from the measured
// state under the ancillary feedback on its distance from the sample's own nominal rollout,
// and scored 0.5 J_nom + 0.5 max(min(J_real, bound), J_nom). Checked against the two rollouts
// and the update written out here in double for the double integrator, and in closed loop.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "mppi/controller.hpp"
#include "tests/mppi/linear_system.hpp"

using mppi::test::DoubleIntegrator;
using mppi::test::QuadraticCost;

namespace {

constexpr int kSamples = 128;
constexpr int kHorizon = 12;
constexpr float kDt = 0.05f;
constexpr float kLo = -3.f, kHi = 3.f;

// The double integrator's step and QuadraticCost's stage cost, in double.
struct Rollout {
  double cost = 0;
  double p = 0, v = 0;
  void step(double u, const QuadraticCost& q) {
    p += kDt * v;
    v += kDt * u;
    cost += q.qp * p * p + q.qv * v * v + q.r * u * u;
  }
};

// Gains K_t = (kp_t, kv_t): time-varying, so that a wrong time index shows.
std::vector<float> test_gains() {
  std::vector<float> k(kHorizon * 2);
  for (int t = 0; t < kHorizon; ++t) {
    k[2 * t] = -3.f + 0.1f * t;
    k[2 * t + 1] = -1.5f - 0.05f * t;
  }
  return k;
}

struct Naive {
  std::vector<double> costs;  // S_k
  std::vector<double> next;   // sum_k w_k V_k
};

// Both rollouts of every sample V_k (v: T x 1 x padded), the combined cost and the update.
Naive naive_augmented(std::span<const float> v, int padded, const float* x_nom0, const float* x_real0,
                      const std::vector<float>& gains, double bound, double lambda, bool augmented) {
  const QuadraticCost q;
  Naive n;
  for (int k = 0; k < kSamples; ++k) {
    Rollout nom{0, x_nom0[0], x_nom0[1]}, real{0, x_real0[0], x_real0[1]};
    for (int t = 0; t < kHorizon; ++t) {
      const double vk = v[static_cast<std::size_t>(t) * padded + k];
      const double u_real = std::clamp(vk + gains[2 * t] * (real.p - nom.p) + gains[2 * t + 1] * (real.v - nom.v),
                                       static_cast<double>(kLo), static_cast<double>(kHi));
      nom.step(vk, q);
      real.step(u_real, q);
    }
    n.costs.push_back(augmented ? 0.5 * nom.cost + 0.5 * std::max(std::min(real.cost, bound), nom.cost) : nom.cost);
  }
  const double min_cost = *std::min_element(n.costs.begin(), n.costs.end());
  double eta = 0;
  std::vector<double> w(kSamples);
  for (int k = 0; k < kSamples; ++k) eta += w[k] = std::exp(-(n.costs[k] - min_cost) / lambda);
  for (int t = 0; t < kHorizon; ++t) {
    double acc = 0;
    for (int k = 0; k < kSamples; ++k) acc += w[k] / eta * v[static_cast<std::size_t>(t) * padded + k];
    n.next.push_back(acc);
  }
  return n;
}

struct IterationResult {
  std::vector<float> costs, next, v;
  int padded = 0;
};

IterationResult iterate_once(const float* x_nom0, const float* x_real0, const std::vector<float>& gains,
                             float bound, float lambda, bool augmented) {
  mppi::CpuBackend<DoubleIntegrator, QuadraticCost> backend(DoubleIntegrator{}, QuadraticCost{}, kSamples, kHorizon,
                                                            kDt, 2);
  const int padded = backend.shape().padded_samples;
  std::vector<float> nominal(kHorizon);
  for (int t = 0; t < kHorizon; ++t) nominal[t] = 0.5f * std::sin(0.4f * t);
  const float std_dev = 1.f, lo = kLo, hi = kHi;
  mppi::IterationInput in;
  in.x0 = {x_nom0, 2};
  in.nominal = nominal;
  in.noise_std = {&std_dev, 1};
  in.control_min = {&lo, 1};
  in.control_max = {&hi, 1};
  in.lambda = lambda;
  in.seed = 5;
  if (augmented) in.augmented = {{x_real0, 2}, gains, bound};
  IterationResult r;
  r.padded = padded;
  r.costs.assign(padded, 0.f);
  r.next.assign(kHorizon, 0.f);
  std::vector<float> weights(padded, 0.f);
  mppi::IterationOutput out;
  out.next = r.next;
  out.costs = r.costs;
  out.weights = weights;
  backend.iterate(in, out);
  REQUIRE(out.valid_samples == kSamples);
  const auto v = backend.sampled_controls();
  r.v.assign(v.begin(), v.end());
  return r;
}

}  // namespace

TEST_CASE("augmented sampling scores each sample by its nominal and its real rollout under the feedback",
          "[core][mppi][tube][rmppi]") {
  const float x_nom0[2] = {1.f, 0.f};
  const float x_real0[2] = {1.4f, -0.6f};
  const auto gains = test_gains();
  const float lambda = 0.5f;
  for (const float bound : {std::numeric_limits<float>::infinity(), 3.f}) {
    INFO("real cost bound " << bound);
    const IterationResult got = iterate_once(x_nom0, x_real0, gains, bound, lambda, true);
    const Naive want = naive_augmented(got.v, got.padded, x_nom0, x_real0, gains, bound, lambda, true);
    int bounded = 0;
    const Naive unbounded = naive_augmented(got.v, got.padded, x_nom0, x_real0, gains,
                                            std::numeric_limits<double>::infinity(), lambda, true);
    for (int k = 0; k < kSamples; ++k) {
      CHECK(got.costs[k] == Approx(want.costs[k]).epsilon(2e-5));
      bounded += want.costs[k] < unbounded.costs[k];
    }
    if (std::isfinite(bound)) CHECK(bounded > 0);  // the bound took effect on some samples
    for (int t = 0; t < kHorizon; ++t) CHECK(got.next[t] == Approx(want.next[t]).margin(2e-5));
  }
}

TEST_CASE("augmented sampling changes the costs only through the real system's distance from the nominal one",
          "[core][mppi][tube][rmppi]") {
  const float x_nom0[2] = {1.f, 0.f};
  const auto gains = test_gains();
  // Real state on the nominal one: the feedback is zero, both rollouts agree, S = J_nom.
  const IterationResult same = iterate_once(x_nom0, x_nom0, gains, 1e30f, 0.5f, true);
  const IterationResult plain = iterate_once(x_nom0, x_nom0, gains, 1e30f, 0.5f, false);
  for (int k = 0; k < kSamples; ++k) CHECK(same.costs[k] == Approx(plain.costs[k]).epsilon(1e-6));
  // Real state off it: the costs are the augmented ones, not the plain ones.
  const float x_real0[2] = {1.4f, -0.6f};
  const IterationResult off = iterate_once(x_nom0, x_real0, gains, 1e30f, 0.5f, true);
  const Naive want_plain = naive_augmented(off.v, off.padded, x_nom0, x_real0, gains, 1e30, 0.5, false);
  int differ = 0;
  for (int k = 0; k < kSamples; ++k) differ += std::abs(off.costs[k] - want_plain.costs[k]) > 1e-3 * want_plain.costs[k];
  CHECK(differ > kSamples / 2);
}

namespace {
mppi::ControllerOptions robust_options(bool augmented) {
  mppi::ControllerOptions o;
  o.num_samples = 512;
  o.horizon = 30;
  o.dt_s = 0.05f;
  o.iterations = 2;
  o.lambda = 0.05f;
  o.noise_std = {1.f};
  o.control_min = {-20.f};
  o.control_max = {20.f};
  o.safe_control = {0.f};
  o.seed = 9;
  o.variant = mppi::ControllerVariant::kRobust;
  o.robust_augmented_sampling = augmented;
  o.ancillary.q_diag = {4.f, 1.f};
  o.ancillary.r_diag = {0.1f};
  o.tube_reset_distance = 10.f;
  return o;
}

// Hides the augmented sampling of a CPU backend (as a GPU backend lacks it).
class NoAugmentedSampling final : public mppi::Backend {
 public:
  explicit NoAugmentedSampling(std::unique_ptr<mppi::Backend> inner) : inner_(std::move(inner)) {}
  const char* name() const override { return "test-gpu"; }
  const mppi::RolloutShape& shape() const override { return inner_->shape(); }
  void rollout(std::span<const float> x0, std::span<const float> v, std::span<float> costs) override {
    inner_->rollout(x0, v, costs);
  }

 private:
  std::unique_ptr<mppi::Backend> inner_;
};
}  // namespace

TEST_CASE("robust MPPI with augmented sampling uses the last step's gains from the second step on",
          "[core][mppi][tube][rmppi]") {
  auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, robust_options(true));
  float x[2] = {1.f, 0.f};
  mppi::StepSummary s;
  c.step(x, &s);
  CHECK_FALSE(s.augmented_sampling);  // no gains yet
  REQUIRE(s.feedback_applied);
  float off[2] = {c.nominal_state()[0] + 0.3f, c.nominal_state()[1] + 0.4f};  // costs more: nominal kept
  const auto u = c.step(off, &s);
  REQUIRE(s.status == mppi::StepStatus::kOk);
  CHECK(s.augmented_sampling);
  CHECK_FALSE(s.nominal_reset);
  CHECK(std::isfinite(u[0]));
  c.reset();
  c.step(x, &s);
  CHECK_FALSE(s.augmented_sampling);  // reset() forgets the gains
}

TEST_CASE("under an unknown push robust MPPI with augmented sampling still regulates", "[core][mppi][tube][rmppi]") {
  // The plant is pushed by a constant 3 m/s^2 the model does not know (as in the tube test).
  auto run = [](mppi::ControllerVariant variant, bool augmented) {
    auto o = robust_options(augmented);
    o.variant = variant;
    auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, o);
    float x[2] = {1.f, 0.f};
    double sum_sq = 0;
    for (int i = 0; i < 80; ++i) {
      mppi::StepSummary s;
      const float u = c.step(x, &s)[0];
      REQUIRE(s.status == mppi::StepStatus::kOk);
      x[0] += 0.05f * x[1];
      x[1] += 0.05f * (u + 3.f);
      if (i >= 40) sum_sq += static_cast<double>(x[0]) * x[0];
    }
    return std::sqrt(sum_sq / 40);
  };
  const double plain = run(mppi::ControllerVariant::kPlain, false);
  const double robust = run(mppi::ControllerVariant::kRobust, false);
  const double augmented = run(mppi::ControllerVariant::kRobust, true);
  INFO("rms position over the last 2 s: plain " << plain << ", robust " << robust << ", robust augmented "
                                                << augmented);
  // measured: plain 0.74, robust 0.51, robust with augmented sampling 0.62. The augmented cost
  // also charges each sample for the real system's excess cost, which the feedback, not the
  // plan, has to remove; it regulates, but here no better than the robust choice alone.
  CHECK(augmented < 0.9 * plain);
  CHECK(robust < plain);
}

TEST_CASE("augmented sampling is refused where it cannot run", "[core][mppi][tube][rmppi]") {
  auto o = robust_options(true);
  std::string why;
  o.variant = mppi::ControllerVariant::kTube;
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("robust_augmented_sampling needs the robust variant") != std::string::npos);
  o.variant = mppi::ControllerVariant::kRobust;
  o.robust_cost_bound = 0.f;
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("robust_cost_bound") != std::string::npos);
  o.robust_cost_bound = std::numeric_limits<float>::quiet_NaN();
  CHECK_FALSE(o.is_valid(1, &why));
  o.robust_cost_bound = std::numeric_limits<float>::infinity();
  REQUIRE(o.is_valid(1, &why));
  auto cpu = [&] {
    return std::make_unique<mppi::CpuBackend<DoubleIntegrator, QuadraticCost>>(
        DoubleIntegrator{}, QuadraticCost{}, o.num_samples, o.horizon, o.dt_s, 1);
  };
  CHECK_THROWS_WITH(mppi::Controller(std::make_unique<NoAugmentedSampling>(cpu()), o, cpu()),
                    Catch::Contains("robust_augmented_sampling") && Catch::Contains("test-gpu"));
  o.robust_augmented_sampling = false;
  CHECK_NOTHROW(mppi::Controller(std::make_unique<NoAugmentedSampling>(cpu()), o, cpu()));
}
