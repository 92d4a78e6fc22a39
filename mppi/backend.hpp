#pragma once
// The one coarse virtual boundary of the data path: roll out a batch of control sequences
// from one start state and return each sequence's total running cost. Behind it, models and
// costs are templates inlined over structure-of-arrays batches (see cpu_backend.hpp).
#include <span>

namespace mppi {

// Sizes fixed when a backend is created.
struct RolloutShape {
  int num_samples = 0;         // K actually used
  int padded_samples = 0;      // K rounded up to the batch width (controls/costs are this long)
  int horizon = 0;             // T
  int num_states = 0;          // model state size
  int num_controls = 0;        // model control size
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual const char* name() const = 0;
  virtual const RolloutShape& shape() const = 0;
  // x0: num_states; controls: T x nu x padded_samples (sample index fastest, already clamped);
  // costs: padded_samples, written (entries >= num_samples are unspecified).
  virtual void rollout(std::span<const float> x0, std::span<const float> controls,
                       std::span<float> costs) = 0;
};

}  // namespace mppi
