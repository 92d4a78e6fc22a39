#pragma once
// CPU backend: OpenMP over chunks of kChunk samples, each chunk rolled out with the model and
// cost inlined over SoA lanes. Scratch memory per thread is allocated once, at construction.
// The chunks go to the threads as the schedule says (mppi/thread_schedule.hpp).
#include <omp.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "mppi/backend.hpp"
#include "mppi/batch.hpp"
#include "mppi/concepts.hpp"
#include "mppi/error.hpp"
#include "mppi/multiversion.hpp"
#include "mppi/thread_schedule.hpp"

namespace mppi {

namespace detail {
// Rolls out samples [k0, k0 + kChunk) of `controls` (T x nu x padded) from x0; cost_out gets
// the kChunk total costs. work: D::kNx*kChunk + D::kNu*kChunk + model scratch floats.
template <class D, class C>
MPPI_MULTIVERSION void rollout_chunk(const D& model, const C& cost, const float* x0,
                                     const float* controls, int padded, int horizon, float dt_s,
                                     int k0, float* work, float* cost_out) noexcept {
  constexpr int W = kChunk;
  float* x = work;                 // kNx x W
  float* u = x + D::kNx * W;       // kNu x W
  float* scratch = u + D::kNu * W;
  for (int i = 0; i < D::kNx; ++i) std::fill_n(x + i * W, W, x0[i]);
  std::fill_n(cost_out, W, 0.f);
  for (int t = 0; t < horizon; ++t) {
    for (int c = 0; c < D::kNu; ++c)
      std::memcpy(u + c * W, controls + (static_cast<std::size_t>(t) * D::kNu + c) * padded + k0,
                  sizeof(float) * W);
    model.template step<W>(Batch<D::kNx, W>{x}, ConstBatch<D::kNu, W>{u}, dt_s, scratch);
    cost.template accumulate<D::kNx, D::kNu, W>(ConstBatch<D::kNx, W>{x}, ConstBatch<D::kNu, W>{u},
                                                t, cost_out);
  }
}
}  // namespace detail

inline int padded_sample_count(int num_samples) {
  return (num_samples + kChunk - 1) / kChunk * kChunk;
}

template <Dynamics D, StageCost<D> C>
class CpuBackend final : public Backend {
 public:
  CpuBackend(D model, C cost, int num_samples, int horizon, float dt_s, int num_threads,
             ThreadSchedule schedule = ThreadSchedule::kDynamic)
      : model_(std::move(model)), cost_(std::move(cost)), dt_s_(dt_s), runner_(num_threads, schedule) {
    if (num_samples < 1 || horizon < 1) throw Error("CpuBackend: need num_samples, horizon >= 1");
    shape_ = {num_samples, padded_sample_count(num_samples), horizon, D::kNx, D::kNu};
    threads_ = runner_.threads();
    work_floats_ = static_cast<std::size_t>((D::kNx + D::kNu) * kChunk) +
                   model_.scratch_floats(kChunk);
    // Round each thread's slice to a cache line (16 floats) so threads never share one.
    work_floats_ = (work_floats_ + 15) / 16 * 16;
    work_.assign(work_floats_ * static_cast<std::size_t>(threads_), 0.f);
  }

  const char* name() const override { return "cpu"; }
  const RolloutShape& shape() const override { return shape_; }
  int num_threads() const { return threads_; }
  const D& model() const { return model_; }
  const C& cost() const { return cost_; }

  bool set_cost_param(std::string_view key, double value, std::string* why) override {
    if constexpr (requires { cost_.set_param(key, value, why); }) return cost_.set_param(key, value, why);
    else return Backend::set_cost_param(key, value, why);
  }
  bool set_cost_map(std::shared_ptr<const CostMap> map, std::string* why) override {
    if constexpr (requires { cost_.set_map(map, why); }) return cost_.set_map(std::move(map), why);
    else return Backend::set_cost_map(std::move(map), why);
  }

  void rollout(std::span<const float> x0, std::span<const float> controls,
               std::span<float> costs) override {
    const int padded = shape_.padded_samples;
    const int chunks = padded / kChunk;
    const float* x0p = x0.data();
    const float* vp = controls.data();
    float* sp = costs.data();
    float* work = work_.data();
    const std::size_t work_floats = work_floats_;
    runner_.run(chunks, 1, [&](int chunk, int slot) {
      detail::rollout_chunk(model_, cost_, x0p, vp, padded, shape_.horizon, dt_s_, chunk * kChunk,
                            work + work_floats * static_cast<std::size_t>(slot), sp + chunk * kChunk);
    });
  }

 private:
  D model_;
  C cost_;
  float dt_s_;
  ParallelRunner runner_;
  RolloutShape shape_;
  int threads_ = 1;
  std::size_t work_floats_ = 0;
  std::vector<float> work_;  // threads x work_floats_
};

}  // namespace mppi
