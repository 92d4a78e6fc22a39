// The CPU backend's fused iteration (CpuBackend::iterate: sampling, rollout and each chunk's
// share of the update in one pass, chunks combined with relative weights) against the two-pass
// form (Controller's sampling pass, CpuBackend::rollout, the update over all samples) and
// against a naive double-precision re-computation of the update law from the samples.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "apps/bench/peer_workload.hpp"
#include "mppi/controller.hpp"
#include "tests/mppi/linear_system.hpp"

namespace {

// Hides iterate() of a CPU backend, so that Controller runs the two-pass form on it.
class RolloutOnly final : public mppi::Backend {
 public:
  explicit RolloutOnly(std::unique_ptr<mppi::Backend> inner) : inner_(std::move(inner)) {}
  const char* name() const override { return "rollout-only"; }
  const mppi::RolloutShape& shape() const override { return inner_->shape(); }
  void rollout(std::span<const float> x0, std::span<const float> v, std::span<float> costs) override {
    inner_->rollout(x0, v, costs);
  }

 private:
  std::unique_ptr<mppi::Backend> inner_;
};

template <class D, class C>
std::unique_ptr<mppi::Backend> cpu_backend(const D& model, const C& cost, const mppi::ControllerOptions& o) {
  return std::make_unique<mppi::CpuBackend<D, C>>(model, cost, o.num_samples, o.horizon, o.dt_s,
                                                  o.num_threads, o.schedule);
}

// The quadratic cost plus NaN for every sample whose control exceeds `nan_above` at some step.
struct NanAboveCost {
  float nan_above = 1e30f;
  template <int Nx, int Nu, int W>
  void accumulate(mppi::ConstBatch<Nx, W> x, mppi::ConstBatch<Nu, W> u, int, float* cost) const noexcept {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j)
      cost[j] += x[0][j] * x[0][j] + 0.1f * x[1][j] * x[1][j] + (u[0][j] > nan_above ? nan : 0.f);
  }
};

// next = sum_k w_k V_k with w from the sampled costs, in double (the update law itself).
struct NaiveUpdate {
  std::vector<double> next, weights;
  double min_cost = 0, sum_sq = 0;
  int valid = 0;
};
NaiveUpdate naive_update(std::span<const float> v, std::span<const float> costs, int k_count,
                         int padded, int rows, double lambda) {
  NaiveUpdate n;
  n.min_cost = std::numeric_limits<double>::infinity();
  for (int k = 0; k < k_count; ++k)
    if (std::isfinite(costs[k])) {
      n.min_cost = std::min<double>(n.min_cost, costs[k]);
      ++n.valid;
    }
  n.weights.assign(k_count, 0.0);
  double eta = 0;
  for (int k = 0; k < k_count; ++k)
    if (std::isfinite(costs[k])) eta += n.weights[k] = std::exp(-(costs[k] - n.min_cost) / lambda);
  n.next.assign(rows, 0.0);
  for (int k = 0; k < k_count; ++k) {
    n.weights[k] /= eta;
    n.sum_sq += n.weights[k] * n.weights[k];
    for (int r = 0; r < rows; ++r) n.next[r] += n.weights[k] * v[static_cast<std::size_t>(r) * padded + k];
  }
  return n;
}

}  // namespace

TEST_CASE("the fused CPU iteration draws the same samples and gives the two-pass update",
          "[core][mppi]") {
  // the peer workload (differential drive, goal + obstacle cost), K not a multiple of the chunk
  mppi::ControllerOptions o = mppi::bench::peer_options(1000, 30, 2);
  o.iterations = GENERATE(1, 2);
  const auto model = mppi::bench::peer_model();
  const auto cost = mppi::bench::peer_cost();
  auto fused = mppi::make_cpu_controller(model, cost, o);
  REQUIRE(fused.backend().has_iterate());
  mppi::Controller two_pass(std::make_unique<RolloutOnly>(cpu_backend(model, cost, o)), o);
  REQUIRE_FALSE(two_pass.backend().has_iterate());
  const int padded = mppi::padded_sample_count(o.num_samples);
  std::vector<float> x = mppi::bench::peer_start_state();
  for (int step = 0; step < 5; ++step) {
    mppi::StepSummary sf, st;
    const auto uf = fused.step(x, &sf);
    const std::vector<float> out_f(uf.begin(), uf.end());
    REQUIRE(sf.status == mppi::StepStatus::kOk);
    if (step == 0 && o.iterations == 1) {
      // the same plan in (the two-pass form later sees a plan that differs by rounding, and a
      // sample a rounding away from a cell edge of the cost map may then cost very differently)
      const auto ut = two_pass.step(x, &st);
      REQUIRE(st.status == mppi::StepStatus::kOk);
      // bit for bit the same draws and costs
      const auto vf = fused.sampled_controls();
      const auto vt = two_pass.sampled_controls();
      REQUIRE(vf.size() == vt.size());
      REQUIRE(vf.size() == static_cast<std::size_t>(o.horizon) * 2 * padded);
      for (std::size_t i = 0; i < vf.size(); ++i) REQUIRE(vf[i] == vt[i]);
      for (int k = 0; k < o.num_samples; ++k) REQUIRE(fused.sampled_costs()[k] == two_pass.sampled_costs()[k]);
      // and the same update up to rounding
      CHECK(sf.valid_samples == st.valid_samples);
      for (int c = 0; c < 2; ++c) CHECK(out_f[c] == Approx(ut[c]).margin(1e-6));
      for (std::size_t i = 0; i < fused.nominal().size(); ++i)
        CHECK(fused.nominal()[i] == Approx(two_pass.nominal()[i]).margin(1e-6));
      CHECK(sf.effective_sample_size == Approx(st.effective_sample_size).epsilon(1e-5));
      CHECK(sf.min_cost == st.min_cost);
      CHECK(sf.mean_cost == Approx(st.mean_cost).epsilon(1e-6));
      for (int k = 0; k < o.num_samples; ++k)
        REQUIRE(fused.weights()[k] == Approx(two_pass.weights()[k]).epsilon(1e-5).margin(1e-9));
    }
    // and the update law from the fused iteration's own samples (last iteration of the step)
    const NaiveUpdate n = naive_update(fused.sampled_controls(), fused.sampled_costs(), o.num_samples,
                                       padded, o.horizon * 2, o.lambda);
    CHECK(out_f[0] == Approx(n.next[0]).margin(2e-6));
    CHECK(out_f[1] == Approx(n.next[1]).margin(2e-6));
    for (int r = 2; r < o.horizon * 2; ++r) CHECK(fused.nominal()[r - 2] == Approx(n.next[r]).margin(2e-6));
    CHECK(sf.effective_sample_size == Approx(1.0 / n.sum_sq).epsilon(1e-4));
    for (int k = 0; k < o.num_samples; ++k) REQUIRE(fused.weights()[k] == Approx(n.weights[k]).margin(1e-6));
    const float us[2] = {out_f[0], out_f[1]};
    model.step<1>(mppi::Batch<3, 1>{x.data()}, mppi::ConstBatch<2, 1>{us}, o.dt_s, nullptr);
  }
}

TEST_CASE("the fused CPU iteration gives NaN-cost samples no weight, and none valid is refused",
          "[core][mppi]") {
  mppi::ControllerOptions o;
  o.num_samples = 333;
  o.horizon = 12;
  o.lambda = 0.05f;
  o.gamma = 0.2f;
  o.noise_std = {0.5f};
  o.control_min = {-2.f};
  o.control_max = {2.f};
  o.safe_control = {0.f};
  o.num_threads = 2;
  NanAboveCost cost;
  cost.nan_above = 0.9f;  // about a quarter of the samples go above at some step
  auto controller = mppi::make_cpu_controller(mppi::test::DoubleIntegrator{}, cost, o);
  const float x0[2] = {1.f, 0.f};
  mppi::StepSummary sum;
  const auto u = controller.step(x0, &sum);
  REQUIRE(sum.status == mppi::StepStatus::kOk);
  const int padded = mppi::padded_sample_count(o.num_samples);
  const NaiveUpdate n = naive_update(controller.sampled_controls(), controller.sampled_costs(),
                                     o.num_samples, padded, o.horizon, o.lambda);
  CHECK(n.valid > 0);
  CHECK(n.valid < o.num_samples - 20);  // the test has NaN samples to skip
  CHECK(sum.valid_samples == n.valid);
  CHECK(sum.min_cost == Approx(n.min_cost).epsilon(1e-6));
  CHECK(u[0] == Approx(n.next[0]).margin(2e-6));
  for (int k = 0; k < o.num_samples; ++k) {
    if (!std::isfinite(controller.sampled_costs()[k])) REQUIRE(controller.weights()[k] == 0.f);
    REQUIRE(controller.weights()[k] == Approx(n.weights[k]).margin(1e-6));
  }
  CHECK(sum.effective_sample_size == Approx(1.0 / n.sum_sq).epsilon(1e-4));

  cost.nan_above = -1e30f;  // every sample NaN
  auto none = mppi::make_cpu_controller(mppi::test::DoubleIntegrator{}, cost, o);
  const auto safe = none.step(x0, &sum);
  CHECK(sum.status == mppi::StepStatus::kNoValidRollout);
  CHECK(sum.valid_samples == 0);
  CHECK(safe[0] == 0.f);
}

TEST_CASE("a chunk's share of the weighted sum equals a double-precision dot product", "[core][mppi]") {
  constexpr int W = mppi::kChunk;
  const std::size_t padded = 3 * W + 64;  // rows further apart than a chunk, as in the controls
  for (int rows : {1, 16, 37, 200}) {
    std::vector<float> e(W), v(static_cast<std::size_t>(rows) * padded), got(rows), portable(rows);
    std::uint32_t h = 12345u;
    const auto next = [&h] {  // uniform in [-1, 1)
      h = h * 1664525u + 1013904223u;
      return static_cast<float>(h >> 8) / 8388608.f - 1.f;
    };
    for (float& x : e) x = 0.5f * (next() + 1.f);
    for (float& x : v) x = next();
    mppi::detail::chunk_partial_sums(e.data(), v.data(), padded, rows, got.data());
    mppi::detail::chunk_partial_sums_portable(e.data(), v.data(), padded, 0, rows, portable.data());
    for (int r = 0; r < rows; ++r) {
      double ref = 0, mag = 0;
      for (int j = 0; j < W; ++j) {
        ref += static_cast<double>(e[j]) * v[static_cast<std::size_t>(r) * padded + j];
        mag += std::abs(static_cast<double>(e[j]) * v[static_cast<std::size_t>(r) * padded + j]);
      }
      REQUIRE(got[r] == Approx(ref).margin(1e-6 * mag));
      REQUIRE(portable[r] == Approx(ref).margin(1e-6 * mag));
    }
  }
}

TEST_CASE("the fused iteration's draws, given again on demand, are the scalar Philox normals it used",
          "[core][mppi]") {
  mppi::ControllerOptions o;
  o.num_samples = 333;  // a partial last chunk and block
  o.horizon = 13;       // an odd horizon: the last step uses half of a Philox call
  o.lambda = 0.5f;
  o.gamma = 0.2f;
  o.noise_std = {0.7f};
  o.control_min = {-1.f};
  o.control_max = {1.5f};
  o.safe_control = {0.f};
  o.num_threads = 2;
  o.seed = 0x1234abcd5678ull;
  auto controller = mppi::make_cpu_controller(mppi::test::DoubleIntegrator{}, NanAboveCost{}, o);
  const float x0[2] = {1.f, 0.f};
  controller.step(x0);
  // the nominal the second step samples around: the first step's plan, shifted by one
  const std::vector<float> nominal(controller.nominal().begin(), controller.nominal().end());
  controller.step(x0);
  const std::vector<int> samples = {0, 1, 15, 16, 17, 200, 63, 64, 330, 332};  // unsorted, block edges
  std::vector<float> some(static_cast<std::size_t>(o.horizon) * samples.size(), -99.f);
  REQUIRE(controller.copy_sampled_controls(samples, some));
  const auto all = controller.sampled_controls();
  const std::size_t padded = static_cast<std::size_t>(mppi::padded_sample_count(o.num_samples));
  REQUIRE(all.size() == static_cast<std::size_t>(o.horizon) * padded);
  // iteration counter of the second step's (only) iteration: one per iteration since reset
  const std::uint32_t iteration = 1;
  for (std::size_t j = 0; j < samples.size(); ++j)
    for (int t = 0; t < o.horizon; ++t) {
      const float n = mppi::normal_at(mppi::NoiseKey{o.seed}, iteration, static_cast<std::uint32_t>(samples[j]),
                                      static_cast<std::uint32_t>(t), 0);
      const float expected = std::clamp(nominal[t] + o.noise_std[0] * n, o.control_min[0], o.control_max[0]);
      REQUIRE(some[t * samples.size() + j] == Approx(expected).margin(1e-6));
      REQUIRE(all[t * padded + static_cast<std::size_t>(samples[j])] == some[t * samples.size() + j]);
    }
  // out of range, or too little room: refused
  std::vector<int> bad = {333};
  CHECK_FALSE(controller.copy_sampled_controls(bad, some));
  bad = {-1};
  CHECK_FALSE(controller.copy_sampled_controls(bad, some));
  CHECK_FALSE(controller.copy_sampled_controls(samples, std::span<float>(some).first(5)));
}
