// mppi-bench: one batched step of the corrected single-track model (WithEffects<SingleTrack>),
// 64 lanes, a horizon of 100 steps at 0.02 s, single thread, from the same spread of driving
// states as BM_PhysicsStep, over a 60 x 60 m area so that the place effects are crossed:
//   BM_CorrectedStep/0  no effect (the wrapper's own cost)
//   BM_CorrectedStep/1  a grip patch of one disc
//   BM_CorrectedStep/2  a grip patch of three discs
//   BM_CorrectedStep/3  a ground bump
// items = lane-steps.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "base/batch.hpp"
#include "base/multiversion.hpp"
#include "dynamics/with_effects.hpp"

namespace {

constexpr int kLanes = mppi::kChunk;
constexpr int kSteps = 100;
using Model = mppi::CorrectedSingleTrack;

MPPI_MULTIVERSION void run_corrected_horizon(const Model& model, float* x, const float* u, float* scratch) {
  for (int t = 0; t < kSteps; ++t)
    model.step<kLanes>(mppi::Batch<Model::kNx, kLanes>{x}, mppi::ConstBatch<Model::kNu, kLanes>{u + t * Model::kNu * kLanes},
                       0.02f, scratch);
}

mppi::EffectParams effects_of(int variant) {
  mppi::EffectParams e;
  if (variant == 1 || variant == 2) {
    e.patch_x_m = 10;
    e.patch_y_m = 5;
    e.patch_radius_m = 8;
    e.patch_grip_scale = 0.6;
  }
  if (variant == 2) {
    e.patch2_x_m = -15;
    e.patch2_radius_m = 6;
    e.patch3_y_m = -20;
    e.patch3_radius_m = 6;
  }
  if (variant == 3) {
    e.bump_x_m = 5;
    e.bump_y_m = -5;
    e.bump_radius_m = 15;
    e.bump_height_m = 0.5;
  }
  return e;
}

void BM_CorrectedStep(benchmark::State& bench) {
  const Model model(mppi::SingleTrack(), effects_of(static_cast<int>(bench.range(0))));
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> U(-1, 1);
  std::vector<float> x0(static_cast<std::size_t>(Model::kNx) * kLanes),
      u(static_cast<std::size_t>(kSteps) * Model::kNu * kLanes);
  for (int j = 0; j < kLanes; ++j) {
    mppi::VehicleState s;
    s.x_m = 30 * U(rng);
    s.y_m = 30 * U(rng);
    s.yaw_rad = 3 * U(rng);
    s.vx_mps = 8 + 7 * U(rng);
    s.vy_mps = U(rng);
    s.yaw_rate_radps = U(rng);
    float lane[Model::kNx];
    model.init_state(s, lane);
    for (int i = 0; i < Model::kNx; ++i) x0[static_cast<std::size_t>(i) * kLanes + j] = lane[i];
  }
  for (auto& v : u) v = U(rng);
  std::vector<float> scratch(std::max<std::size_t>(1, model.scratch_floats(kLanes)));
  std::vector<float> x = x0;
  for (auto _ : bench) {
    x = x0;
    run_corrected_horizon(model, x.data(), u.data(), scratch.data());
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
  bench.SetItemsProcessed(bench.iterations() * kLanes * kSteps);
}

BENCHMARK(BM_CorrectedStep)->DenseRange(0, 3);

}  // namespace
