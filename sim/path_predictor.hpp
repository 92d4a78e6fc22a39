#pragma once
// A PathPredictor (sim/step_observer.hpp) from a dynamics model: rolls out up to kChunk control
// sequences as one batch with the model's own step, at the controller's time step, and keeps x, y.
// For drawing: it runs off the control thread, on a copy of the model.
#include <algorithm>
#include <memory>
#include <vector>

#include "base/batch.hpp"
#include "mppi/concepts.hpp"
#include "sim/step_observer.hpp"

namespace mppi::sim {

template <Dynamics D>
PathPredictor make_path_predictor(const D& model, float dt_s) {
  auto shared = std::make_shared<const D>(model);
  return [shared, dt_s](std::span<const float> x0, std::span<const float> controls, int count,
                        std::span<float> xy_out) {
    constexpr int W = kChunk;
    const D& m = *shared;
    count = std::clamp(count, 0, W);
    if (count == 0 || x0.size() < static_cast<std::size_t>(D::kNx)) return;
    const int horizon = static_cast<int>(controls.size() / (static_cast<std::size_t>(D::kNu) * count));
    if (xy_out.size() < static_cast<std::size_t>(count) * (horizon + 1) * 2) return;
    std::vector<float> x(static_cast<std::size_t>(D::kNx) * W), u(static_cast<std::size_t>(D::kNu) * W, 0.f);
    std::vector<float> scratch(std::max<std::size_t>(1, m.scratch_floats(W)));
    for (int i = 0; i < D::kNx; ++i) std::fill_n(x.data() + i * W, W, x0[i]);
    auto record = [&](int t) {
      for (int j = 0; j < count; ++j) {
        float* p = xy_out.data() + (static_cast<std::size_t>(j) * (horizon + 1) + t) * 2;
        p[0] = x[state::kX * W + j];
        p[1] = x[state::kY * W + j];
      }
    };
    record(0);
    for (int t = 0; t < horizon; ++t) {
      for (int c = 0; c < D::kNu; ++c)
        std::copy_n(controls.data() + (static_cast<std::size_t>(t) * D::kNu + c) * count, count, u.data() + c * W);
      m.template step<W>(Batch<D::kNx, W>{x.data()}, ConstBatch<D::kNu, W>{u.data()}, dt_s, scratch.data());
      record(t + 1);
    }
  };
}

}  // namespace mppi::sim
