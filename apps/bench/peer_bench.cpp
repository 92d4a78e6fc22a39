// Peer benchmark: the MPPI-Generic cross-implementation workload (apps/bench/peer_workload.hpp) and
// the scaling of the AutoRally network workload, in mppi-bench.
//
//   BM_PeerIteration/K/T/threads   one controller.step(x): fresh noise, rollouts + cost, weights,
//                                  update; closed loop (the state moves on with the returned
//                                  control, like MPPI-Generic's plant). Every step is timed on its
//                                  own: counters mean_ms, median_ms, p99_ms, max_ms (wall clock);
//                                  the reported time is the mean (manual time).
//   BM_PeerNoise/K/T/threads       drawing the K x T x 2 clamped perturbed controls only
//   BM_PeerPhilox/K/T/threads      the Philox4x32-10 words of that noise only (one call per
//                                  sample and pair of time steps: 2 controls use words 0, 1 at
//                                  the even step and 2, 3 at the odd one)
//   BM_PeerNormals/K/T/threads     Philox + Box-Muller (the normals, not yet clamped / stored)
//   BM_PeerRollout/K/T/threads     backend rollout with the cost (no sampling, no update)
//   BM_PeerDynamics/K/T/threads    backend rollout, model only (cost = 0)
//   BM_AutoRallyScaling/K/T/threads  BM_PeerIteration's timing for the AutoRally network +
//                                  AutoRallyCost on the Gazebo map (open loop, fixed state)
// scripts/peer_compare.py prints BM_PeerIteration beside the published figures.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/multiversion.hpp"
#include "costs/autorally_cost.hpp"
#include "dynamics/autorally_nn.hpp"
#include "mppi/controller.hpp"
#include "mppi/cpu_backend.hpp"
#include "mppi/noise.hpp"
#include "peer_workload.hpp"

namespace {

using mppi::bench::peer_cost;
using mppi::bench::peer_model;
using mppi::bench::peer_options;

struct ZeroCost {
  template <int Nx, int Nu, int W>
  void accumulate(mppi::ConstBatch<Nx, W>, mppi::ConstBatch<Nu, W>, int, float*) const noexcept {}
};

// Per-step wall times -> mean / median / p99 / max counters (milliseconds) and manual time.
class StepTimer {
 public:
  explicit StepTimer(benchmark::State& state) : state_(state) { times_.reserve(1 << 16); }
  void start() { t0_ = std::chrono::steady_clock::now(); }
  void stop() {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    times_.push_back(s);
    state_.SetIterationTime(s);
  }
  void report() {
    if (times_.empty()) return;
    std::vector<double> t = times_;
    std::sort(t.begin(), t.end());
    double sum = 0;
    for (double v : t) sum += v;
    const auto at = [&](double q) {
      const auto i = static_cast<std::size_t>(q * static_cast<double>(t.size() - 1) + 0.5);
      return t[std::min(i, t.size() - 1)] * 1e3;
    };
    state_.counters["mean_ms"] = sum / static_cast<double>(t.size()) * 1e3;
    state_.counters["median_ms"] = at(0.5);
    state_.counters["p99_ms"] = at(0.99);
    state_.counters["max_ms"] = t.back() * 1e3;
    state_.counters["steps"] = static_cast<double>(t.size());
  }

 private:
  benchmark::State& state_;
  std::vector<double> times_;
  std::chrono::steady_clock::time_point t0_;
};

void set_shape_counters(benchmark::State& state, int k, int t, int threads) {
  state.counters["K"] = k;
  state.counters["T"] = t;
  state.counters["threads"] = threads;
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * k * t);
}

void BM_PeerIteration(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0)), horizon = static_cast<int>(state.range(1)),
            threads = static_cast<int>(state.range(2));
  const mppi::DiffDrive model = peer_model();
  mppi::Controller controller =
      mppi::make_cpu_controller(model, peer_cost(), peer_options(k, horizon, threads));
  const std::vector<float> start = mppi::bench::peer_start_state();
  std::vector<float> x = start;
  mppi::StepSummary summary;
  for (int i = 0; i < 5; ++i) controller.step(x, &summary);  // warm caches and the thread pool
  controller.reset();
  StepTimer timer(state);
  int steps = 0;
  for (auto _ : state) {
    timer.start();
    const std::span<const float> u = controller.step(x, &summary);
    timer.stop();
    // plant: the model itself, one dt with the returned control (not timed)
    float xs[3] = {x[0], x[1], x[2]};
    float us[2] = {u[0], u[1]};
    model.step<1>(mppi::Batch<3, 1>{xs}, mppi::ConstBatch<2, 1>{us}, 0.02f, nullptr);
    x.assign(xs, xs + 3);
    if (++steps == 10000) {  // MPPI-Generic runs 10,000 iterations from the start
      x = start;
      controller.reset();
      steps = 0;
    }
  }
  timer.report();
  set_shape_counters(state, k, horizon, threads);
  state.counters["min_cost"] = summary.min_cost;
  state.counters["ess"] = summary.effective_sample_size;
  if (summary.status != mppi::StepStatus::kOk) state.SkipWithError(summary.reason);
}

void BM_PeerNoise(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0)), horizon = static_cast<int>(state.range(1)),
            threads = static_cast<int>(state.range(2));
  const mppi::ControllerOptions o = peer_options(k, horizon, threads);
  const int nu = 2, padded = mppi::padded_sample_count(k), chunks = padded / mppi::kChunk;
  std::vector<float> nominal(static_cast<std::size_t>(horizon) * nu, 0.1f);
  std::vector<float> controls(nominal.size() * padded), control_cost(padded);
  std::uint32_t iteration = 0;
  for (auto _ : state) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int c = 0; c < chunks; ++c)
      mppi::detail::sample_chunk(mppi::NoiseKey{o.seed}, iteration, c * mppi::kChunk, k, padded,
                                 horizon, nu, nominal.data(), o.noise_std.data(),
                                 o.control_min.data(), o.control_max.data(), o.gamma,
                                 controls.data(), control_cost.data());
    ++iteration;
    benchmark::ClobberMemory();
  }
  set_shape_counters(state, k, horizon, threads);
}

// The noise kernel's stages for one chunk of kChunk samples and every t. Multiversioned like
// sample_chunk, so that Box-Muller gets the same vector width as in the controller.
template <bool kBoxMuller>
MPPI_MULTIVERSION float noise_stage_chunk(std::uint32_t iteration, int chunk, int horizon) noexcept {
  alignas(64) std::uint32_t words[4 * mppi::kChunk];
  alignas(64) float normals[4 * mppi::kChunk];
  float acc = 0.f;
  for (int t = 0; t < horizon; t += 2) {
    const int steps = std::min(2, horizon - t);
    if constexpr (kBoxMuller) {
      mppi::normal_block<mppi::kChunk>(mppi::NoiseKey{1}, iteration, static_cast<std::uint32_t>(chunk * mppi::kChunk),
                                       static_cast<std::uint32_t>(t / 2), 0u, normals, steps);
      acc += normals[t % mppi::kChunk];
    } else {
      mppi::detail::philox_words_dispatch<mppi::kChunk>(1u, 0u, iteration, static_cast<std::uint32_t>(chunk * mppi::kChunk),
                                                        static_cast<std::uint32_t>(t / 2), 0u, words, 2 * steps);
      acc += static_cast<float>(words[t % mppi::kChunk]);
    }
  }
  return acc;
}

template <bool kBoxMuller>
void noise_stage(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0)), horizon = static_cast<int>(state.range(1)),
            threads = static_cast<int>(state.range(2));
  const int chunks = mppi::padded_sample_count(k) / mppi::kChunk;
  std::uint32_t iteration = 0;
  std::vector<float> sink(static_cast<std::size_t>(chunks), 0.f);
  for (auto _ : state) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int c = 0; c < chunks; ++c) sink[c] += noise_stage_chunk<kBoxMuller>(iteration, c, horizon);
    ++iteration;
    benchmark::DoNotOptimize(sink.data());
  }
  set_shape_counters(state, k, horizon, threads);
}
void BM_PeerPhilox(benchmark::State& state) { noise_stage<false>(state); }
void BM_PeerNormals(benchmark::State& state) { noise_stage<true>(state); }

template <class Cost>
void peer_rollout(benchmark::State& state, Cost cost) {
  const int k = static_cast<int>(state.range(0)), horizon = static_cast<int>(state.range(1)),
            threads = static_cast<int>(state.range(2));
  const mppi::ControllerOptions o = peer_options(k, horizon, threads);
  mppi::CpuBackend<mppi::DiffDrive, Cost> backend(peer_model(), std::move(cost), k, horizon, o.dt_s,
                                                  threads);
  const int nu = 2, padded = backend.shape().padded_samples;
  std::vector<float> nominal(static_cast<std::size_t>(horizon) * nu, 0.f);
  for (int t = 0; t < horizon; ++t) nominal[t * nu] = 0.3f;
  std::vector<float> controls(nominal.size() * padded), control_cost(padded), costs(padded);
  for (int k0 = 0; k0 < padded; k0 += mppi::kChunk)
    mppi::detail::sample_chunk(mppi::NoiseKey{o.seed}, 0, k0, k, padded, horizon, nu, nominal.data(),
                               o.noise_std.data(), o.control_min.data(), o.control_max.data(),
                               o.gamma, controls.data(), control_cost.data());
  const std::vector<float> x0 = mppi::bench::peer_start_state();
  for (auto _ : state) {
    backend.rollout(x0, controls, costs);
    benchmark::DoNotOptimize(costs.data());
    benchmark::ClobberMemory();
  }
  set_shape_counters(state, k, horizon, threads);
}
void BM_PeerRollout(benchmark::State& state) { peer_rollout(state, peer_cost()); }
void BM_PeerDynamics(benchmark::State& state) { peer_rollout(state, ZeroCost{}); }

// ---- the AutoRally network workload at other K and T ----
std::string data_path(const std::string& relative) { return std::string(MPPI_BENCH_DATA_DIR) + "/" + relative; }

void BM_AutoRallyScaling(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0)), horizon = static_cast<int>(state.range(1)),
            threads = static_cast<int>(state.range(2));
  static const mppi::AutoRallyNetwork net =
      mppi::AutoRallyNetwork::load(data_path("autorally/models/autorally_nnet_09_12_2018.npz"));
  static const auto map = std::make_shared<const mppi::CostMap>(
      mppi::CostMap::load_npz(data_path("autorally/maps/gazebo/gazebo_costmap.npz")));
  mppi::ControllerOptions o;
  o.num_samples = k;
  o.horizon = horizon;
  o.num_threads = threads;
  mppi::Controller controller = mppi::make_cpu_controller(net, mppi::AutoRallyCost(map), o);
  mppi::VehicleState s;  // on the Gazebo centreline, as in BM_MppiIteration
  s.x_m = -8.5f;
  s.y_m = -8.9f;
  s.yaw_rad = 2.3561945f;
  s.vx_mps = 5.f;
  std::vector<float> x0(mppi::AutoRallyNetwork::kNx, 0.f);
  net.init_state(s, x0.data());
  mppi::StepSummary summary;
  for (int i = 0; i < 3; ++i) controller.step(x0, &summary);
  StepTimer timer(state);
  for (auto _ : state) {
    timer.start();
    auto u = controller.step(x0, &summary);
    benchmark::DoNotOptimize(u.data());
    timer.stop();
  }
  timer.report();
  set_shape_counters(state, k, horizon, threads);
  if (summary.status != mppi::StepStatus::kOk) state.SkipWithError(summary.reason);
}

constexpr int kPeerSamples[] = {128, 256, 512, 1024, 2048, 4096, 6144, 8192, 16384};

void peer_k_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"K", "T", "threads"});
  for (int threads : {1, 2}) {
    for (int k : kPeerSamples) b->Args({k, 100, threads});
    for (int t : {25, 50, 200, 400}) b->Args({2048, t, threads});
  }
  b->UseManualTime()->Unit(benchmark::kMillisecond);
}
void peer_part_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"K", "T", "threads"});
  for (int threads : {1, 2})
    for (int k : {2048, 16384}) b->Args({k, 100, threads});
  b->UseRealTime()->Unit(benchmark::kMillisecond);
}
void autorally_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"K", "T", "threads"});
  for (int threads : {1, 2}) {
    for (int k : {512, 1024, 2048, 4096, 8192}) b->Args({k, 100, threads});
    for (int t : {25, 50, 200}) b->Args({1920, t, threads});
  }
  b->UseManualTime()->Unit(benchmark::kMillisecond);
}

BENCHMARK(BM_PeerIteration)->Apply(peer_k_args);
BENCHMARK(BM_PeerNoise)->Apply(peer_part_args);
BENCHMARK(BM_PeerPhilox)->Apply(peer_part_args);
BENCHMARK(BM_PeerNormals)->Apply(peer_part_args);
BENCHMARK(BM_PeerRollout)->Apply(peer_part_args);
BENCHMARK(BM_PeerDynamics)->Apply(peer_part_args);
BENCHMARK(BM_AutoRallyScaling)->Apply(autorally_args);

}  // namespace
