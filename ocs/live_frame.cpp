#include "ocs/live_frame.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mppi/controller.hpp"

namespace mppi::ocs {

void LiveFrame::reserve(int num_states, int num_controls, int horizon_steps) {
  model_state.reserve(static_cast<std::size_t>(num_states));
  controls.reserve(static_cast<std::size_t>(horizon_steps) * num_controls * kPathsPerFrame);
  weights.reserve(kPathsPerFrame);
}

int pick_rollouts(std::span<const float> weights, std::span<int> indices) {
  const int k_count = static_cast<int>(weights.size());
  const int wanted = std::min(static_cast<int>(indices.size()), k_count);
  if (wanted <= 0) return 0;
  int best = 0;
  for (int k = 1; k < k_count; ++k)
    if (weights[k] > weights[best]) best = k;
  // Evenly spread indices; the one nearest the best is replaced by the best.
  int nearest = 0;
  for (int i = 0; i < wanted; ++i) {
    indices[i] = static_cast<int>((static_cast<long>(i) * k_count) / wanted);
    if (std::abs(indices[i] - best) < std::abs(indices[nearest] - best)) nearest = i;
  }
  indices[nearest] = best;
  return wanted;
}

void capture_paths(const Controller& controller, std::span<const float> first_control, LiveFrame& frame) {
  const ControllerOptions& o = controller.options();
  const int nu = static_cast<int>(first_control.size());
  const int horizon = o.horizon;
  const std::span<const float> all_weights = controller.weights();
  const std::size_t rows = static_cast<std::size_t>(horizon) * nu;
  std::array<int, kPathsPerFrame - 1> picked{};
  int rollouts = pick_rollouts(all_weights, picked);
  frame.horizon = horizon;
  frame.nu = nu;
  // The picked samples' controls first, packed (rows x rollouts), then spread in place to
  // rows x paths with the plan in column 0: each value moves to a higher index, so copying
  // from the last one down never overwrites one not yet moved.
  frame.controls.resize(rows * (1 + static_cast<std::size_t>(rollouts)));  // within the reserved capacity
  if (rollouts > 0 &&
      !controller.copy_sampled_controls(std::span<const int>(picked.data(), static_cast<std::size_t>(rollouts)),
                                        frame.controls))
    rollouts = 0;  // this backend keeps no samples
  const int paths = 1 + rollouts;
  frame.paths = paths;
  frame.controls.resize(rows * paths);
  frame.weights.resize(static_cast<std::size_t>(paths));
  float* c = frame.controls.data();
  for (std::size_t r = rows; r-- > 0;)
    for (int j = rollouts; j-- > 0;) c[r * paths + 1 + j] = c[r * rollouts + j];
  // The plan this step optimised: its first control was output, the rest is now nominal[0..].
  const std::span<const float> nominal = controller.nominal();
  for (int t = 0; t < horizon; ++t)
    for (int ch = 0; ch < nu; ++ch)
      c[(static_cast<std::size_t>(t) * nu + ch) * paths] =
          t == 0 ? first_control[ch] : nominal[static_cast<std::size_t>(t - 1) * nu + ch];
  frame.weights[0] = std::numeric_limits<float>::quiet_NaN();
  for (int j = 0; j < rollouts; ++j) frame.weights[1 + j] = all_weights[picked[j]];
}

}  // namespace mppi::ocs
