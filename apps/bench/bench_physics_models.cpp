// mppi-bench: one batched model step of each physics model, 64 lanes (one rollout chunk), in
// a horizon of 100 steps at the controller's 0.02 s, single thread:
//   BM_PhysicsStep<SingleTrack>, <DoubleTrack>, <FullVehicle>   items = lane-steps
// From a spread of driving states (1-15 m/s, sliding) with random controls, as rollouts see.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "base/batch.hpp"
#include "base/multiversion.hpp"
#include "dynamics/double_track.hpp"
#include "dynamics/full_vehicle.hpp"
#include "dynamics/single_track.hpp"

namespace {

constexpr int kLanes = mppi::kChunk;
constexpr int kSteps = 100;

template <class M>
MPPI_MULTIVERSION void run_horizon(const M& model, float* x, const float* u) {
  for (int t = 0; t < kSteps; ++t)
    model.template step<kLanes>(mppi::Batch<M::kNx, kLanes>{x}, mppi::ConstBatch<M::kNu, kLanes>{u + t * M::kNu * kLanes},
                                0.02f, nullptr);
}

template <class M>
void BM_PhysicsStep(benchmark::State& bench) {
  const M model;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> U(-1, 1);
  std::vector<float> x0(static_cast<std::size_t>(M::kNx) * kLanes), u(static_cast<std::size_t>(kSteps) * M::kNu * kLanes);
  for (int j = 0; j < kLanes; ++j) {
    mppi::VehicleState s;
    s.vx_mps = 8 + 7 * U(rng);
    s.vy_mps = U(rng);
    s.yaw_rate_radps = U(rng);
    float lane[M::kNx];
    model.init_state(s, lane);
    for (int i = 0; i < M::kNx; ++i) x0[static_cast<std::size_t>(i) * kLanes + j] = lane[i];
  }
  for (auto& v : u) v = U(rng);
  std::vector<float> x = x0;
  for (auto _ : bench) {
    x = x0;
    run_horizon(model, x.data(), u.data());
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
  bench.SetItemsProcessed(bench.iterations() * kLanes * kSteps);
}

BENCHMARK_TEMPLATE(BM_PhysicsStep, mppi::SingleTrack);
BENCHMARK_TEMPLATE(BM_PhysicsStep, mppi::DoubleTrack);
BENCHMARK_TEMPLATE(BM_PhysicsStep, mppi::FullVehicle);

}  // namespace
