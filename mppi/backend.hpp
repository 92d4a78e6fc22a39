#pragma once
// The one coarse virtual boundary of the data path: roll out a batch of control sequences
// from one start state and return each sequence's total running cost. Behind it, models and
// costs are templates inlined over structure-of-arrays batches (see cpu_backend.hpp).
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "mppi/actuator_chain.hpp"
#include "mppi/ancillary.hpp"
#include "mppi/cost_map.hpp"
#include "mppi/sampler.hpp"

namespace mppi {

// Sizes fixed when a backend is created.
struct RolloutShape {
  int num_samples = 0;         // K actually used
  int padded_samples = 0;      // K rounded up to the batch width (controls/costs are this long)
  int horizon = 0;             // T
  int num_states = 0;          // model state size
  int num_controls = 0;        // model control size
};

// Robust MPPI's augmented sampling (Gandhi et al. 2021; ControllerOptions::
// robust_augmented_sampling). Beside each sample's rollout from IterationInput::x0 (the nominal
// state), the real system is rolled out from real_x0 under the sample's controls plus the
// ancillary feedback on its distance from that sample's own nominal rollout:
//   u_real_t = clamp(V_t + K_t (x_real_t - x_nom_t)),
// and the sample's cost is
//   S = 0.5 J_nom + 0.5 max(min(J_real, real_cost_bound), J_nom) + control cost,
// so that a sequence the real car cannot follow from where it is costs more, while the bound
// keeps one hopeless real rollout from swamping the rest. Off when real_x0 is empty.
struct AugmentedSampling {
  std::span<const float> real_x0;  // num_states: the measured state
  std::span<const float> gains;    // T x nu x nx, row-major: K_t along the plan
  float real_cost_bound = std::numeric_limits<float>::infinity();
  bool enabled() const { return !real_x0.empty(); }
};

// One whole MPPI iteration done by the backend (a GPU backend: sampling, rollouts and the
// weighted update without round trips). Inputs as in Controller; see Backend::iterate().
struct IterationInput {
  std::span<const float> x0;           // num_states
  std::span<const float> nominal;      // T x nu, row-major
  std::span<const float> noise_std;    // nu
  std::span<const float> control_min;  // nu
  std::span<const float> control_max;  // nu
  float gamma = 0.f;                   // control-cost weight
  float lambda = 1.f;                  // temperature
  std::uint64_t seed = 0;              // Philox key (the same numbers as the CPU path)
  std::uint32_t iteration = 0;         // Philox counter word 2
  NoiseFilter noise_filter;            // the sampler's recursion over the normals (white: none)
  ActuatorPlan actuators;              // the actuators between command and model (none: off)
  AugmentedSampling augmented;         // Robust MPPI's real-system rollouts (none: off)
};
struct IterationOutput {
  std::span<float> next;     // T x nu: sum_k w_k V_k (before smoothing)
  std::span<float> costs;    // padded: total cost S_k of each sample (first K valid)
  std::span<float> weights;  // padded: normalised weights (first K valid)
  float min_cost = 0.f;      // min of the finite S_k
  float mean_cost = 0.f;     // mean of the finite S_k
  float sum_sq_weights = 0.f;  // sum_k w_k^2
  int valid_samples = 0;     // samples with a finite S_k (0: next is not usable)
};

// out[r * n + j] = all[r * padded + samples[j]] for the rows r in [0, rows) of a T x nu x padded
// array of sampled controls (n = samples.size()). False (out unspecified) if all or out is too
// small or a sample is outside [0, num_samples).
inline bool copy_sample_columns(std::span<const float> all, std::size_t rows, std::size_t padded,
                                int num_samples, std::span<const int> samples, std::span<float> out) {
  const std::size_t n = samples.size();
  if (all.size() < rows * padded || out.size() < rows * n) return false;
  for (int k : samples)
    if (k < 0 || k >= num_samples) return false;
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t j = 0; j < n; ++j) out[r * n + j] = all[r * padded + static_cast<std::size_t>(samples[j])];
  return true;
}

class Backend {
 public:
  virtual ~Backend() = default;
  virtual const char* name() const = 0;
  virtual const RolloutShape& shape() const = 0;
  // x0: num_states; controls: T x nu x padded_samples (sample index fastest, already clamped);
  // costs: padded_samples, written (entries >= num_samples are unspecified).
  virtual void rollout(std::span<const float> x0, std::span<const float> controls,
                       std::span<float> costs) = 0;
  // True if iterate() works: then Controller hands each iteration over whole.
  virtual bool has_iterate() const { return false; }
  // True if iterate() rolls out through IterationInput::actuators.
  virtual bool supports_actuators() const { return false; }
  // True if iterate() rolls out the real system of IterationInput::augmented.
  virtual bool supports_augmented_sampling() const { return false; }
  // Samples V_k = clamp(U + eps_k) with the Philox numbers of mppi/noise.hpp, rolls out, and
  // forms the weights and the weighted sum, as Controller does on the CPU.
  virtual void iterate(const IterationInput& /*in*/, IterationOutput& /*out*/) {}
  // The controls sampled by the last iterate() (T x nu x padded), if the backend keeps them.
  virtual std::span<const float> sampled_controls() const { return {}; }
  // The controls the last iterate() sampled for samples[j] (each in [0, num_samples)):
  // out[(t * nu + c) * n + j], n = samples.size(). False (out unspecified) if the backend keeps
  // none, a sample is out of range or out is too small.
  virtual bool copy_sampled_controls(std::span<const int> samples, std::span<float> out) const {
    const RolloutShape& s = shape();
    return copy_sample_columns(sampled_controls(), static_cast<std::size_t>(s.horizon) * s.num_controls,
                               static_cast<std::size_t>(s.padded_samples), s.num_samples, samples, out);
  }

  // The cost changed while the controller runs (between iterations, from the thread that
  // steps it): one parameter by its key, or the cost map. False with the reason in *why if
  // the cost has no such parameter, the value is out of range, or this backend cannot change
  // its cost; nothing changes then.
  virtual bool set_cost_param(std::string_view /*key*/, double /*value*/, std::string* why) {
    if (why) *why = std::string(name()) + " backend: its cost cannot change while it runs";
    return false;
  }
  virtual bool set_cost_map(std::shared_ptr<const CostMap> /*map*/, std::string* why) {
    if (why) *why = std::string(name()) + " backend: its cost map cannot change while it runs";
    return false;
  }

  // A parameter of the model changed while the controller runs (online adaptation, e.g. the
  // AutoRally network's "lateral_force_scale"). False with the reason in *why if the model has
  // no such parameter, the value is out of range or this backend cannot change its model.
  virtual bool set_model_param(std::string_view /*key*/, double /*value*/, std::string* why) {
    if (why) *why = std::string(name()) + " backend: its model cannot change while it runs";
    return false;
  }
  // One model step of dt from x0 (num_states) under the model input u (num_controls, after the
  // actuators) into x1 (num_states), with the model as it is now. False with the reason in *why
  // if a size is wrong or this backend cannot step its model on its own.
  virtual bool predict_step(std::span<const float> /*x0*/, std::span<const float> /*u*/,
                            std::span<float> /*x1*/, std::string* why) {
    if (why) *why = std::string(name()) + " backend cannot step its model on its own";
    return false;
  }

  // The ancillary feedback of Tube-MPPI / Robust MPPI along a plan: rolls `nominal` (T x nu)
  // out from x0 (num_states) into states_out ((T+1) x nx: x0 .. x_T) and writes the
  // time-varying LQR gains of the model linearised along it into gains_out (T x nu x nx,
  // row-major), so that u_t = nominal_t + K_t (x_t - states_out_t); see mppi/lqr.hpp. False
  // with the reason in *why (naming the argument) if a size is wrong, an input is not finite,
  // the weights do not fit, the recursion fails, or this backend cannot linearise its model.
  // Called between iterations, from the thread that steps the controller.
  virtual bool ancillary_gains(std::span<const float> /*x0*/, std::span<const float> /*nominal*/,
                               const AncillaryWeights& /*w*/, std::span<float> /*states_out*/,
                               std::span<float> /*gains_out*/, std::string* why) {
    if (why) *why = std::string(name()) + " backend cannot linearise its model";
    return false;
  }
  // True if ancillary_gains() and plan_cost() work (Tube-MPPI and Robust MPPI need them).
  virtual bool supports_feedback() const { return false; }
  // The running cost of one control sequence `plan` (T x nu) rolled out from x0, into *cost.
  // False with the reason in *why if this backend cannot, or a size is wrong.
  virtual bool plan_cost(std::span<const float> /*x0*/, std::span<const float> /*plan*/, float* /*cost*/,
                         std::string* why) {
    if (why) *why = std::string(name()) + " backend cannot cost a single plan";
    return false;
  }
};

}  // namespace mppi
