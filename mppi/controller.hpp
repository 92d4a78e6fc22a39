#pragma once
// The MPPI controller (the paper's sidebar "Model Predictive Path Integral Control"):
//   V_k = clamp(U + eps_k),  eps_k ~ N(0, Sigma) per channel and time step
//   S_k = rollout cost of V_k + gamma * sum_t u_t^T Sigma^-1 (V_k,t - u_t)
//   w_k = exp(-(S_k - min S) / lambda) / eta,  U <- sum_k w_k V_k  (then optional smoothing)
// repeated `iterations` times per step; the first control is returned and U shifted one step
// (warm start). Buffers are allocated once in the constructor; step() allocates nothing.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string_view>
#include <string>
#include <utility>
#include <vector>

#include "base/error.hpp"
#include "base/multiversion.hpp"
#include "mppi/actuator_chain.hpp"
#include "mppi/adaptive_temperature.hpp"
#include "mppi/backend.hpp"
#include "mppi/controller_options.hpp"
#include "mppi/cpu_backend.hpp"
#include "mppi/fault_injection.hpp"
#include "mppi/lateral_force_adaptation.hpp"
#include "mppi/noise.hpp"
#include "mppi/savitzky_golay.hpp"
#include "mppi/thread_schedule.hpp"

namespace mppi {

enum class StepStatus {
  kOk = 0,
  kInvalidState,     // the start state had a NaN/inf: safe control returned, plan kept
  kNoValidRollout,   // every sampled cost was NaN/inf: safe control returned
  kBackendError,     // the backend failed (e.g. a lost GPU device): safe control returned; with
                     // a fallback backend set, the following steps run on it
};

struct StepSummary {
  StepStatus status = StepStatus::kOk;
  const char* reason = "";           // human-readable; valid until the next step() call
  bool backend_switched = false;     // this step's failure moved the controller to its fallback
  float min_cost = 0.f;              // best sampled total cost (last iteration)
  float mean_cost = 0.f;             // mean of the finite sampled costs (last iteration)
  float effective_sample_size = 0.f; // 1 / sum w^2 (last iteration), in [1, K]
  int valid_samples = 0;             // samples with a finite cost (last iteration)
  int iterations = 0;                // iterations run
  float lambda = 0.f;                // temperature of the weights (last iteration)
  // Tube / robust variants: the distance sqrt(dx' Q dx) of the measured state from the nominal
  // one, and whether the nominal state was put back on the measured one this step.
  float tube_distance = 0.f;
  bool nominal_reset = false;
  bool feedback_applied = false;     // the ancillary gains were computed and applied
  // Robust MPPI with robust_augmented_sampling: the samples were also rolled out as the real
  // system under the feedback (not at the first step, which has no gains yet)
  bool augmented_sampling = false;
  // Online adaptation (ControllerOptions::force_adaptation): the estimated scale of the model's
  // lateral force this step planned with (1 when the adaptation is off).
  float lateral_force_scale = 1.f;
  double optimizer_ms = 0.0;         // wall time of step()
};

namespace detail {
// Draws V = clamp(U + std * eps) for samples [k0, k0 + kChunk) and every t (eps: the sampler's
// filtered normals, mppi/sampler.hpp); control cost per lane.
MPPI_MULTIVERSION inline void sample_chunk(const NoiseKey& key, std::uint32_t iteration, int k0,
                                           int num_samples, int padded, int horizon, int nu,
                                           const float* nominal, const float* noise_std,
                                           const float* lo, const float* hi, float gamma,
                                           float* controls, float* control_cost,
                                           const NoiseFilter& filter = {}) noexcept {
  constexpr int W = kChunk;
  alignas(64) float acc[W] = {};
  alignas(64) float eps_state[kMaxNoiseChannels * W];
  const float valid_lanes = static_cast<float>(num_samples - k0);  // lanes j >= this get no noise
  const auto stride = static_cast<std::size_t>(padded);
  for (int t = 0; t < horizon; t += 2)
    sample_step_pair<W>(key, iteration, k0, valid_lanes, t, std::min(2, horizon - t), nu, nominal + t * nu,
                        noise_std, lo, hi, gamma, filter, eps_state,
                        controls + static_cast<std::size_t>(t) * nu * stride + k0, stride,
                        static_cast<std::size_t>(nu) * stride, acc);
  std::copy_n(acc, W, control_cost + k0);
}
}  // namespace detail

namespace detail {
// sum_k w_k v_k in one fixed order. Not inlined: every schedule and thread count runs this same
// code, so the sum (and the controls) do not depend on them.
[[gnu::noinline]] inline float weighted_row(const float* w, const float* v, int k_count) noexcept {
  float acc = 0.f;
#pragma omp simd reduction(+ : acc)
  for (int k = 0; k < k_count; ++k) acc += w[k] * v[k];
  return acc;
}
}  // namespace detail

class Controller {
 public:
  // Takes any backend; throws mppi::Error if the options are invalid for it.
  // A change of backend after a failure: at which step() call, from which backend to which, and
  // the failure that caused it.
  struct BackendSwitch {
    std::uint64_t step_call = 0;  // 0-based count of step() calls (reset() does not restart it)
    std::string from, to, reason;
  };

  // `feedback_backend` (optional) serves the tube variants' linearisation and plan costs when
  // `backend` cannot (a GPU backend: make_controller() adds a CPU backend of the same model
  // and cost); it sees the same cost changes.
  Controller(std::unique_ptr<Backend> backend, ControllerOptions options,
             std::unique_ptr<Backend> feedback_backend = nullptr)
      : backend_(std::move(backend)), feedback_backend_(std::move(feedback_backend)), options_(std::move(options)) {
    if (!backend_) throw Error("Controller: no backend");
    const RolloutShape& s = backend_->shape();
    std::string why;
    if (!options_.is_valid(s.num_controls, &why)) throw Error("ControllerOptions: " + why);
    if (s.num_samples != options_.num_samples || s.horizon != options_.horizon)
      throw Error("Controller: backend shape (K, T) does not match the options");
    nu_ = s.num_controls;
    nx_ = s.num_states;
    padded_ = s.padded_samples;
    runner_ = std::make_unique<ParallelRunner>(options_.num_threads, options_.schedule);
    threads_ = runner_->threads();
    nominal_.assign(static_cast<std::size_t>(options_.horizon) * nu_, 0.f);
    next_.assign(nominal_.size(), 0.f);
    // the sampling pass's buffer; a backend that iterates (CPU, GPU) keeps its own
    if (!backend_->has_iterate()) controls_.assign(nominal_.size() * padded_, 0.f);
    costs_.assign(padded_, 0.f);
    control_costs_.assign(padded_, 0.f);
    weights_.assign(padded_, 0.f);
    output_.assign(nu_, 0.f);
    x0_.assign(nx_, 0.f);
    if (options_.smoothing_window > 0)
      smoother_ = SavitzkyGolay(options_.horizon, options_.smoothing_window, options_.smoothing_order);
    noise_filter_ = make_noise_filter(options_.sampler, options_.dt_s);
    lambda_ = options_.lambda;
    if (options_.variant != ControllerVariant::kPlain) {
      if (!linearising_backend())
        throw Error(std::string("ControllerOptions: the ") + variant_name(options_.variant) +
                    " variant needs a backend that linearises its model (the CPU backend, or a CPU "
                    "feedback backend beside the rollout backend); the " +
                    backend_->name() + " backend does not and no feedback backend was given");
      if (feedback_backend_ && feedback_backend_.get() == linearising_backend() &&
          (feedback_backend_->shape().horizon != options_.horizon ||
           feedback_backend_->shape().num_states != nx_ || feedback_backend_->shape().num_controls != nu_))
        throw Error("Controller: the feedback backend's horizon, states and controls must match the rollout backend's");
      if (!check_ancillary_weights(options_.ancillary, nx_, nu_, &why)) throw Error("ControllerOptions: " + why);
      nominal_state_.assign(nx_, 0.f);
      measured_.assign(nx_, 0.f);
      nominal_states_.assign(static_cast<std::size_t>(options_.horizon + 1) * nx_, 0.f);
      gains_.assign(static_cast<std::size_t>(options_.horizon) * nu_ * nx_, 0.f);
      // size the backend's work for the feedback now, so that step() allocates nothing
      float unused = 0.f;
      linearising_backend()->ancillary_gains(nominal_state_, nominal_, options_.ancillary, nominal_states_, gains_, nullptr);
      linearising_backend()->plan_cost(nominal_state_, nominal_, &unused, nullptr);
      if (options_.robust_augmented_sampling) {
        if (!backend_->supports_augmented_sampling())
          throw Error(std::string("ControllerOptions: robust_augmented_sampling needs a backend that rolls out the "
                                  "real system inside every sample (the CPU backend); the ") +
                      backend_->name() + " backend does not");
        sampling_gains_.assign(gains_.size(), 0.f);
      }
    }
    if (!options_.actuators.empty()) {
      if (!backend_->supports_actuators())
        throw Error(std::string("ControllerOptions: actuator-aware planning needs a backend that rolls out "
                                "through the actuators (the CPU or the Vulkan backend); the ") +
                    backend_->name() + " backend does not");
      for (const ActuatorChannel& c : options_.actuators) actuator_steps_.push_back(actuator_step(c, options_.dt_s));
    }
    acting_input_.assign(nu_, 0.f);
    if (options_.force_adaptation.enabled) {
      if (nx_ < state::kCommonStates)
        throw Error("ControllerOptions: lateral force adaptation needs a vehicle model (its first " +
                    std::to_string(state::kCommonStates) + " states the common ones), the model has " +
                    std::to_string(nx_) + " states");
      if (options_.force_adaptation.scale_model)
        for (Backend* b : {backend_.get(), feedback_backend_.get()})
          if (b && !b->set_model_param(kLateralForceScaleParam, 1.0, &why))
            throw Error("ControllerOptions: lateral force adaptation with scale_model needs a model parameter \"" +
                        std::string(kLateralForceScaleParam) + "\" that the backend can set: " + why);
      force_estimator_ = LateralForceScaleEstimator(options_.force_adaptation);
      if (nu_ > control::kThrottle) throttle_max_configured_ = options_.control_max[control::kThrottle];
      adapt_previous_.assign(nx_, 0.f);
      adapt_predicted_.assign(nx_, 0.f);
      if (!backend_->predict_step(adapt_previous_, acting_input_, adapt_predicted_, &why))
        throw Error("ControllerOptions: lateral force adaptation: " + why);
    }
    reset();
  }

  // One control step from the full model state x0 (num_states floats). Returns the control to
  // apply now (num_controls floats, valid until the next call). Never returns NaN and never
  // throws: a backend failure gives StepStatus::kBackendError, the safe control and the
  // backend's message as the reason (and the switch to the fallback backend, if one is set).
  std::span<const float> step(std::span<const float> x0, StepSummary* summary = nullptr) noexcept {
    const auto start = std::chrono::steady_clock::now();
    StepSummary local;
    StepSummary& sum = summary ? *summary : local;
    sum = StepSummary{};
    sum.lateral_force_scale = force_scale_;
    ++step_calls_;
    bool finite = x0.size() == static_cast<std::size_t>(nx_);
    for (std::size_t i = 0; finite && i < x0.size(); ++i) finite = std::isfinite(x0[i]);
    if (!finite) {
      adapt_have_previous_ = false;
      sum.status = StepStatus::kInvalidState;
      sum.reason = x0.size() != static_cast<std::size_t>(nx_) ? "state has the wrong size"
                                                               : "state contains NaN or inf";
      return safe_output(sum, start);
    }
    std::copy(x0.begin(), x0.end(), x0_.begin());
    adapt_model(sum);
    if (feedback()) choose_nominal_state(sum);
    try {
      // A cold plan (first step after construction or reset) gets the warm-start iterations
      // first, with noise counters of their own (the top half of the counter space).
      const int warm = cold_plan_ ? options_.warm_start_iterations : 0;
      for (int it = 0; it < warm + options_.iterations; ++it) {
        const auto iteration =
            it < warm ? static_cast<std::uint32_t>(0x80000000u + (warm_starts_ * warm + static_cast<std::uint64_t>(it)) % 0x80000000u)
                      : static_cast<std::uint32_t>(step_index_ * options_.iterations + (it - warm));
        if (backend_->has_iterate()) {
          if (!device_iteration(iteration, sum)) return safe_output(sum, start);
        } else {
          sample(iteration);
          backend_->rollout(x0_, controls_, costs_);
          if (!update_nominal(sum)) return safe_output(sum, start);
        }
        sum.iterations = it + 1;
      }
    } catch (const std::exception& e) {
      return backend_failed(e.what(), sum, start);
    } catch (...) {
      return backend_failed("unknown exception", sum, start);
    }
    std::copy_n(nominal_.begin(), nu_, output_.begin());
    for (int c = 0; c < nu_; ++c) {
      if (!std::isfinite(output_[c])) {  // not expected: the plan is a clamped mean of finite values
        sum.status = StepStatus::kNoValidRollout;
        sum.reason = "the plan held NaN or inf; it was reset";
        reset_plan();
        return safe_output(sum, start);
      }
    }
    if (feedback()) apply_feedback(sum);
    if (cold_plan_ && options_.warm_start_iterations > 0) ++warm_starts_;
    cold_plan_ = false;
    sent(output_);
    shift_nominal();
    ++step_index_;
    sum.optimizer_ms = elapsed_ms(start);
    return output_;
  }

  // Change the cost while running, keeping the warm-started plan: one parameter by its key
  // (AutoRallyCost: the keys of data/config/autorally_cost.yaml, e.g. "target_speed_mps"), or
  // the cost map. Call between steps, from the thread that steps. False, with the reason in
  // *why, if the key is unknown, the value out of range or the backend cannot change its cost;
  // the cost is then unchanged.
  // The changes are kept and applied again to a fallback backend when the controller switches.
  // With the lateral force adaptation on, its speed parameter (options().force_adaptation
  // .speed_param) is the requested speed: the cost gets it x scale^speed_exponent.
  bool set_cost_param(std::string_view key, double value, std::string* why = nullptr) {
    const double requested = value;
    if (governs(key)) value *= speed_factor();
    if (!guarded(why, [&] { return backend_->set_cost_param(key, value, why); })) return false;
    if (governs(key)) {
      requested_speed_ = requested;
      governed_speed_ = value;
    }
    if (feedback_backend_ && !guarded(why, [&] { return feedback_backend_->set_cost_param(key, value, why); }))
      return false;
    remember_cost_param(key, value);
    return true;
  }
  // The speed the host asked for through set_cost_param (NaN if none) and the one the cost has,
  // with the lateral force adaptation on.
  double requested_speed() const { return requested_speed_; }
  double governed_speed() const { return governed_speed_; }
  bool set_cost_map(std::shared_ptr<const CostMap> map, std::string* why = nullptr) {
    if (!guarded(why, [&] { return backend_->set_cost_map(map, why); })) return false;
    if (feedback_backend_ && !guarded(why, [&] { return feedback_backend_->set_cost_map(map, why); })) return false;
    cost_map_ = std::move(map);
    return true;
  }

  // The backend to use when the current one fails (a lost GPU device): `make` builds it at the
  // first failure (make_controller() sets the CPU backend for the same model and cost). The
  // cost changes made so far are applied to it; the plan is kept.
  void set_fallback_backend(std::function<std::unique_ptr<Backend>()> make) {
    make_fallback_ = std::move(make);
  }
  bool has_fallback_backend() const { return static_cast<bool>(make_fallback_); }
  // The backend changes so far (at most one: the fallback is used once).
  const std::vector<BackendSwitch>& backend_switches() const { return switches_; }

  // Fault injection for tests and drills: after `healthy_steps` more steps (counted as backend
  // calls, one per iteration) the backend fails like a lost device, and stays failed.
  void inject_device_loss(std::uint64_t healthy_steps) {
    backend_ = std::make_unique<DeviceLossInjector>(
        std::move(backend_), healthy_steps * static_cast<std::uint64_t>(options_.iterations));
  }

  // Forget the plan (nominal = zero controls clamped to the limits) and the actuators' state
  // (at rest: every input 0, nothing pending).
  // The adapted lateral force scale is kept: the car and the surface are the same after a
  // respawn.
  void reset() {
    reset_plan();
    step_index_ = 0;
    actuator_state_ = ActuatorState{};
    have_nominal_state_ = false;
    have_sampling_gains_ = false;
    adapt_have_previous_ = false;
  }

  // The estimated scale of the model's lateral force now (ControllerOptions::force_adaptation;
  // 1 when off); the model itself has it only with force_adaptation.scale_model.
  float lateral_force_scale() const { return force_scale_; }

  // Tube / robust variants: the plan's states from the nominal state ((T + 1) x nx) and the
  // feedback gains along it (T x nu x nx, u_t = u_nom_t + K_t (x_t - x_nom_t)) of the last
  // step, published with the plan (as AutoRally's plant publishes its DDP gains) so that a
  // loop on the chassis can apply them between plans. Empty for the plain controller. The
  // plan they belong to is the one before the shift: nominal() after the step holds it from
  // t = 1 on.
  std::span<const float> nominal_states() const { return nominal_states_; }
  std::span<const float> feedback_gains() const { return gains_; }
  std::span<const float> nominal_state() const { return nominal_state_; }

  // The actuator chain's state (options().actuators): the commands sent but not yet acting and
  // the rate limiter's and the lag's outputs. step() advances it with every command it returns;
  // set it where the real actuators are measured (a servo's position) or were reset.
  const ActuatorState& actuator_state() const { return actuator_state_; }
  void set_actuator_state(const ActuatorState& s) { actuator_state_ = s; }
  // The temperature the next iteration starts from (options().lambda unless adaptive).
  float temperature() const { return lambda_; }

  std::span<const float> nominal() const { return nominal_; }  // T x nu, row-major
  // The sampled sequences and costs of the last iteration (T x nu x padded; padded).
  // (With a backend that iterates on the device, the backend's copy, or empty if it keeps none.)
  std::span<const float> sampled_controls() const {
    return backend_->has_iterate() ? backend_->sampled_controls() : std::span<const float>(controls_);
  }
  // A few samples' sequences of the last iteration: out[(t * nu + c) * n + j] for samples[j]
  // (n = samples.size(), each in [0, num_samples)). Cheaper than sampled_controls() when the
  // backend draws them again on demand. False if none are kept or an argument is out of range.
  bool copy_sampled_controls(std::span<const int> samples, std::span<float> out) const {
    if (backend_->has_iterate()) return backend_->copy_sampled_controls(samples, out);
    return copy_sample_columns(controls_, nominal_.size(), static_cast<std::size_t>(backend_->shape().padded_samples),
                               options_.num_samples, samples, out);
  }
  std::span<const float> sampled_costs() const { return std::span(costs_).first(options_.num_samples); }
  std::span<const float> weights() const { return std::span(weights_).first(options_.num_samples); }
  const ControllerOptions& options() const { return options_; }
  Backend& backend() { return *backend_; }
  std::uint64_t step_index() const { return step_index_; }

 private:
  void sample(std::uint32_t iteration) {
    const NoiseKey key{options_.seed};
    const int chunks = padded_ / kChunk;
    const float gamma = options_.gamma;
    runner_->run(chunks, 1, [&](int chunk, int) {
      detail::sample_chunk(key, iteration, chunk * kChunk, options_.num_samples, padded_,
                           options_.horizon, nu_, nominal_.data(), options_.noise_std.data(),
                           options_.control_min.data(), options_.control_max.data(), gamma,
                           controls_.data(), control_costs_.data(), noise_filter_);
    });
  }

  // Exponential weights and the weighted average. False if no sample has a finite cost.
  bool update_nominal(StepSummary& sum) {
    const int k_count = options_.num_samples;
    float min_cost = std::numeric_limits<float>::infinity();
    int valid = 0;
    double cost_sum = 0.0;
    for (int k = 0; k < k_count; ++k) {
      const float s = costs_[k] + control_costs_[k];
      costs_[k] = s;
      if (std::isfinite(s)) {
        min_cost = std::min(min_cost, s);
        cost_sum += s;
        ++valid;
      }
    }
    sum.valid_samples = valid;
    if (valid == 0) {
      sum.status = StepStatus::kNoValidRollout;
      sum.reason = "every sampled rollout cost was NaN or infinite";
      return false;
    }
    if (adaptive()) lambda_ = solve_temperature(std::span<const float>(costs_).first(k_count), options_.temperature, lambda_);
    sum.lambda = lambda_;
    sum.min_cost = min_cost;
    sum.mean_cost = static_cast<float>(cost_sum / valid);
    sum.effective_sample_size = exponential_weights(min_cost, lambda_);
    weighted_sum(controls_.data());
    commit_next();
    return true;
  }

  bool adaptive() const { return options_.temperature.ess_share > 0.f; }
  bool feedback() const { return options_.variant != ControllerVariant::kPlain; }

  // sqrt((a - b)' Q (a - b)) with the ancillary Q (identity when not given).
  float weighted_distance(const float* a, const float* b) const {
    double d2 = 0.0;
    for (int i = 0; i < nx_; ++i) {
      const double q = options_.ancillary.q_diag.empty() ? 1.0 : options_.ancillary.q_diag[i];
      d2 += q * (static_cast<double>(a[i]) - b[i]) * (static_cast<double>(a[i]) - b[i]);
    }
    return static_cast<float>(std::sqrt(d2));
  }

  // The backend that linearises the model and costs single plans: the rollout backend if it
  // can, else the feedback backend given at construction; nullptr if neither.
  Backend* linearising_backend() const noexcept {
    if (backend_->supports_feedback()) return backend_.get();
    return feedback_backend_ && feedback_backend_->supports_feedback() ? feedback_backend_.get() : nullptr;
  }

  // The state the iterations plan from (x0_ on return): the nominal state, or the measured
  // one where the variant's rule puts the nominal state back on it.
  void choose_nominal_state(StepSummary& sum) noexcept {
    bool reset = !have_nominal_state_;
    if (!reset) {
      sum.tube_distance = weighted_distance(x0_.data(), nominal_state_.data());
      reset = !(sum.tube_distance <= options_.tube_reset_distance);
    }
    if (!reset && options_.variant == ControllerVariant::kRobust) {
      // Robust MPPI: the measured state unless the plan costs more from it than from the
      // nominal state (by more than the margin); a backend error keeps the nominal state.
      float cost_measured = 0.f, cost_nominal = 0.f;
      try {
        Backend* feedback = linearising_backend();
        if (feedback && feedback->plan_cost(x0_, nominal_, &cost_measured, nullptr) &&
            feedback->plan_cost(nominal_state_, nominal_, &cost_nominal, nullptr))
          reset = !(cost_measured > cost_nominal + options_.robust_cost_margin);
      } catch (...) {
      }
    }
    if (reset) std::copy(x0_.begin(), x0_.end(), nominal_state_.begin());
    sum.nominal_reset = reset;
    measured_.assign(x0_.begin(), x0_.end());  // capacity nx: no allocation after the first step
    std::copy(nominal_state_.begin(), nominal_state_.end(), x0_.begin());
    have_nominal_state_ = true;
  }

  // output_ <- clamp(u_nom_0 + K_0 (x - x_nom)); the nominal state moves on under u_nom_0. If
  // the gains cannot be formed, u_nom_0 goes out and the next step plans from the measured state.
  void apply_feedback(StepSummary& sum) noexcept {
    bool ok = false;
    try {
      Backend* feedback = linearising_backend();
      ok = feedback && feedback->ancillary_gains(nominal_state_, nominal_, options_.ancillary, nominal_states_, gains_, nullptr);
    } catch (...) {
    }
    if (!ok) {
      have_nominal_state_ = false;
      have_sampling_gains_ = false;
      return;
    }
    keep_sampling_gains();
    for (int c = 0; c < nu_; ++c) {
      double u = output_[c];
      for (int i = 0; i < nx_; ++i)
        u += static_cast<double>(gains_[static_cast<std::size_t>(c) * nx_ + i]) * (measured_[i] - nominal_state_[i]);
      const auto uc = static_cast<float>(u);
      if (std::isfinite(uc)) output_[c] = std::clamp(uc, options_.control_min[c], options_.control_max[c]);
    }
    std::copy_n(nominal_states_.begin() + nx_, nx_, nominal_state_.begin());
    sum.feedback_applied = true;
  }

  // Augmented sampling: the next step's samples run the feedback along the plan shifted by one
  // step, as the plan is, so they use these gains shifted the same way (the last one repeated).
  void keep_sampling_gains() noexcept {
    if (sampling_gains_.empty()) return;
    const std::size_t per_step = static_cast<std::size_t>(nu_) * nx_;
    std::copy(gains_.begin() + static_cast<std::ptrdiff_t>(per_step), gains_.end(), sampling_gains_.begin());
    std::copy(gains_.end() - static_cast<std::ptrdiff_t>(per_step), gains_.end(),
              sampling_gains_.end() - static_cast<std::ptrdiff_t>(per_step));
    have_sampling_gains_ = true;
  }

  // weights_ <- exp(-(S_k - min_cost) / lambda) / eta over costs_ (0 where not finite);
  // returns the effective sample size 1 / sum w^2.
  float exponential_weights(float min_cost, float lambda) {
    const int k_count = options_.num_samples;
    const float inv_lambda = 1.f / lambda;
    double eta = 0.0;
    for (int k = 0; k < k_count; ++k) {
      const float s = costs_[k];
      const float w = std::isfinite(s) ? std::exp(-(s - min_cost) * inv_lambda) : 0.f;
      weights_[k] = w;
      eta += w;
    }
    double sum_sq = 0.0;
    const auto inv_eta = static_cast<float>(1.0 / eta);  // eta >= 1: the best sample has w = 1
    for (int k = 0; k < k_count; ++k) {
      weights_[k] *= inv_eta;
      sum_sq += static_cast<double>(weights_[k]) * weights_[k];
    }
    return static_cast<float>(1.0 / sum_sq);
  }

  // U <- sum_k w_k V_k into next_ (v: T x nu x padded).
  void weighted_sum(const float* v) {
    const int k_count = options_.num_samples;

    // U <- sum_k w_k V_k: one row (t, c) per task, summed over k in a fixed order, so the
    // result does not depend on the thread count.
    const int rows = options_.horizon * nu_;
    float* next = next_.data();
    const float* w = weights_.data();
    const int padded = padded_;
    runner_->run(rows, 8, [&](int row, int) {
      next[row] = detail::weighted_row(w, v + static_cast<std::size_t>(row) * padded, k_count);
    });
  }

  // The whole iteration on the backend (device noise, rollouts, weights, weighted sum); the
  // smoothing and clamping stay here. False if no sample has a finite cost.
  bool device_iteration(std::uint32_t iteration, StepSummary& sum) {
    IterationInput in;
    in.x0 = x0_;
    in.nominal = nominal_;
    in.noise_std = options_.noise_std;
    in.control_min = options_.control_min;
    in.control_max = options_.control_max;
    in.gamma = options_.gamma;
    in.lambda = options_.lambda;
    in.seed = options_.seed;
    in.iteration = iteration;
    in.lambda = lambda_;
    in.noise_filter = noise_filter_;
    if (!actuator_steps_.empty()) in.actuators = {actuator_steps_.data(), &actuator_state_};
    if (have_sampling_gains_) {
      in.augmented = {measured_, sampling_gains_, options_.robust_cost_bound};
      sum.augmented_sampling = true;
    }
    IterationOutput out;
    out.next = next_;
    out.costs = costs_;
    out.weights = weights_;
    backend_->iterate(in, out);
    sum.valid_samples = out.valid_samples;
    bool usable = out.valid_samples > 0;
    for (std::size_t i = 0; usable && i < next_.size(); ++i) usable = std::isfinite(next_[i]);
    if (!usable) {
      sum.status = StepStatus::kNoValidRollout;
      sum.reason = "every sampled rollout cost was NaN or infinite";
      return false;
    }
    sum.min_cost = out.min_cost;
    sum.mean_cost = out.mean_cost;
    sum.effective_sample_size = 1.f / out.sum_sq_weights;
    sum.lambda = lambda_;
    if (adaptive()) retemper(out.min_cost, sum);
    commit_next();
    return true;
  }

  // Adaptive temperature after a backend's iteration, which weighted with lambda_: the
  // temperature that meets the target on this iteration's costs becomes lambda_; if the
  // weights used missed the target by more than the tolerance, they and next_ are formed again
  // at it from the sampled controls (drawn again by the CPU backend).
  void retemper(float min_cost, StepSummary& sum) {
    const auto costs = std::span<const float>(costs_).first(options_.num_samples);
    const float want = options_.temperature.ess_share * static_cast<float>(options_.num_samples);
    if (std::abs(sum.effective_sample_size - want) <= options_.temperature.tolerance * want) return;  // met: lambda_ stands
    lambda_ = solve_temperature(costs, options_.temperature, lambda_);
    const std::span<const float> v = backend_->sampled_controls();
    if (v.size() < next_.size() * static_cast<std::size_t>(padded_)) return;  // keeps none: weights stand
    sum.effective_sample_size = exponential_weights(min_cost, lambda_);
    sum.lambda = lambda_;
    weighted_sum(v.data());
  }

  // nominal <- next_ (smoothed and clamped if smoothing is on).
  void commit_next() {
    if (smoother_.enabled()) {
      for (int c = 0; c < nu_; ++c) smoother_.apply(next_.data() + c, nominal_.data() + c, nu_);
      for (int t = 0; t < options_.horizon; ++t)
        for (int c = 0; c < nu_; ++c)
          nominal_[t * nu_ + c] = std::clamp(nominal_[t * nu_ + c], options_.control_min[c],
                                             options_.control_max[c]);
    } else {
      std::copy(next_.begin(), next_.end(), nominal_.begin());
    }
  }

  // The command goes out: the actuator chain moves on by one step; the model's input until the
  // next step is the chain's output (or the command itself without a chain).
  void sent(std::span<const float> command) {
    if (!actuator_steps_.empty()) {
      advance_actuators(actuator_steps_.data(), nu_, command.data(), actuator_state_);
      std::copy_n(actuator_state_.lag_out, nu_, acting_input_.begin());
    } else {
      std::copy(command.begin(), command.end(), acting_input_.begin());
    }
  }

  // Online adaptation of the model's lateral force (mppi/lateral_force_adaptation.hpp): the
  // model's step from the last measured state under the input that acted, against the state
  // measured now (x0_). A backend that fails here fails again in the iteration that follows,
  // which handles it; the scale then stays.
  void adapt_model(StepSummary& sum) noexcept {
    if (!options_.force_adaptation.enabled) return;
    if (adapt_have_previous_) {
      try {
        if (backend_->predict_step(adapt_previous_, acting_input_, adapt_predicted_, nullptr)) {
          const float scale = force_estimator_.update(adapt_previous_.data(), adapt_predicted_.data(), x0_.data(),
                                                      options_.dt_s, model_scale_);
          if (scale != force_scale_) {
            force_scale_ = scale;
            if (options_.force_adaptation.scale_model && backend_->set_model_param(kLateralForceScaleParam, scale, nullptr)) {
              if (feedback_backend_) feedback_backend_->set_model_param(kLateralForceScaleParam, scale, nullptr);
              model_scale_ = scale;
            }
            govern_speed();
            govern_throttle();
          }
        }
      } catch (...) {
      }
    }
    std::copy(x0_.begin(), x0_.end(), adapt_previous_.begin());
    adapt_have_previous_ = true;
    sum.lateral_force_scale = force_scale_;
  }

  // The target speed the cost gets: the requested one x scale^speed_exponent, sent again when it moved by
  // more than 0.5 % (the cost's parameter is a float; no allocation).
  void govern_speed() {
    if (!std::isfinite(requested_speed_)) return;
    const double speed = requested_speed_ * speed_factor();
    if (std::abs(speed - governed_speed_) <= 0.005 * std::abs(requested_speed_)) return;
    const std::string_view key = options_.force_adaptation.speed_param;
    if (!backend_->set_cost_param(key, speed, nullptr)) return;
    if (feedback_backend_) feedback_backend_->set_cost_param(key, speed, nullptr);
    governed_speed_ = speed;
    for (auto& [k, v] : cost_params_)
      if (k == key) v = speed;
  }
  // The throttle's upper limit: the configured one x scale^throttle_exponent, above the lower
  // limit and the safe control's throttle.
  void govern_throttle() noexcept {
    if (!(options_.force_adaptation.throttle_exponent > 0.f) || nu_ <= control::kThrottle) return;
    const int c = control::kThrottle;
    const float factor = std::pow(force_scale_, options_.force_adaptation.throttle_exponent);
    const float floor = std::max(options_.control_min[c], options_.safe_control[c]) + 1e-3f;
    options_.control_max[c] = std::max(throttle_max_configured_ * factor, floor);
  }
  double speed_factor() const {
    return std::pow(static_cast<double>(force_scale_), static_cast<double>(options_.force_adaptation.speed_exponent));
  }
  bool governs(std::string_view key) const {
    return options_.force_adaptation.enabled && !options_.force_adaptation.speed_param.empty() &&
           key == options_.force_adaptation.speed_param;
  }

  void shift_nominal() {
    std::copy(nominal_.begin() + nu_, nominal_.end(), nominal_.begin());
    // the last step keeps its previous value (the tail of the plan repeats)
  }

  void reset_plan() {
    cold_plan_ = true;
    for (int t = 0; t < options_.horizon; ++t)
      for (int c = 0; c < nu_; ++c)
        nominal_[t * nu_ + c] = std::clamp(0.f, options_.control_min[c], options_.control_max[c]);
  }

  void remember_cost_param(std::string_view key, double value) {
    auto same_key = [&](const auto& kv) { return kv.first == key; };
    const auto it = std::find_if(cost_params_.begin(), cost_params_.end(), same_key);
    if (it != cost_params_.end()) it->second = value;
    else cost_params_.emplace_back(std::string(key), value);
  }

  // Runs a backend call that may throw; an exception becomes false with its message in *why.
  template <class F>
  bool guarded(std::string* why, F&& call) {
    try {
      return call();
    } catch (const std::exception& e) {
      if (why) *why = std::string(backend_->name()) + " backend failed: " + e.what();
    } catch (...) {
      if (why) *why = std::string(backend_->name()) + " backend failed: unknown exception";
    }
    return false;
  }

  // A backend call threw: safe control, the message as the reason, and the fallback backend
  // from the next step on (if one is set and has not been used yet). Never throws: if even the
  // message cannot be stored, the reason stays a static text.
  std::span<const float> backend_failed(const char* what, StepSummary& sum,
                                        std::chrono::steady_clock::time_point start) noexcept {
    sum.status = StepStatus::kBackendError;
    sum.reason = "the backend failed";
    try {
      failure_reason_ = std::string(backend_->name()) + " backend failed: " + what;
      sum.reason = failure_reason_.c_str();
      if (make_fallback_) {
        auto make = std::move(make_fallback_);
        make_fallback_ = nullptr;
        std::unique_ptr<Backend> fallback = make();
        if (fallback) {
          std::string why;
          for (const auto& [key, value] : cost_params_)
            if (!fallback->set_cost_param(key, value, &why))
              failure_reason_ += "; the fallback refused cost parameter " + key + ": " + why;
          if (cost_map_ && !fallback->set_cost_map(cost_map_, &why))
            failure_reason_ += "; the fallback refused the cost map: " + why;
          if (options_.force_adaptation.scale_model &&
              !fallback->set_model_param(kLateralForceScaleParam, model_scale_, &why))
            failure_reason_ += "; the fallback refused the lateral force scale: " + why;
          switches_.push_back({step_calls_ - 1, backend_->name(), fallback->name(), failure_reason_});
          backend_ = std::move(fallback);
          if (!backend_->has_iterate() && controls_.empty())
            controls_.assign(nominal_.size() * padded_, 0.f);
          sum.backend_switched = true;
          sum.reason = failure_reason_.c_str();
        }
      }
    } catch (...) {
      // no fallback then; the safe control still goes out
    }
    return safe_output(sum, start);
  }

  std::span<const float> safe_output(StepSummary& sum,
                                     std::chrono::steady_clock::time_point start) {
    std::copy(options_.safe_control.begin(), options_.safe_control.end(), output_.begin());
    sent(output_);
    sum.optimizer_ms = elapsed_ms(start);
    return output_;
  }

  static double elapsed_ms(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
  }

  std::unique_ptr<Backend> backend_;
  std::unique_ptr<Backend> feedback_backend_;  // optional: linearises for a backend that cannot
  ControllerOptions options_;
  int nu_ = 0, nx_ = 0, padded_ = 0, threads_ = 1;
  std::unique_ptr<ParallelRunner> runner_;  // the CPU threads of sampling and the weighted sum
  std::uint64_t step_index_ = 0;
  std::uint64_t step_calls_ = 0;      // step() calls since construction
  std::function<std::unique_ptr<Backend>()> make_fallback_;
  std::vector<BackendSwitch> switches_;
  std::string failure_reason_;        // StepSummary::reason of the last backend failure
  std::vector<std::pair<std::string, double>> cost_params_;  // cost changes, latest per key
  std::shared_ptr<const CostMap> cost_map_;
  std::vector<float> nominal_;        // T x nu
  std::vector<float> next_;           // T x nu, the unsmoothed update
  std::vector<float> controls_;       // T x nu x padded
  std::vector<float> costs_;          // padded
  std::vector<float> control_costs_;  // padded
  std::vector<float> weights_;        // padded
  std::vector<float> output_;         // nu
  std::vector<float> x0_;             // nx
  SavitzkyGolay smoother_;
  NoiseFilter noise_filter_;          // the sampler (options_.sampler at dt_s)
  float lambda_ = 1.f;                // the temperature of the next iteration
  std::vector<ActuatorStep> actuator_steps_;  // options_.actuators at dt_s; empty = off
  ActuatorState actuator_state_;
  // tube / robust variants
  std::vector<float> nominal_state_;   // nx: the state the next step plans from
  bool have_nominal_state_ = false;    // false: the next step starts it at the measured state
  bool cold_plan_ = true;              // the plan is reset_plan()'s zeros: warm-start iterations due
  std::uint64_t warm_starts_ = 0;      // warm starts run (their noise counters follow on)
  std::vector<float> measured_;        // nx: this step's measured state
  std::vector<float> nominal_states_;  // (T + 1) x nx along the last plan
  std::vector<float> gains_;           // T x nu x nx
  // robust_augmented_sampling: the gains the next step's samples use (T x nu x nx)
  std::vector<float> sampling_gains_;
  bool have_sampling_gains_ = false;
  // the model's input until the next step (nu): the command sent, after the actuators
  std::vector<float> acting_input_;
  // online adaptation (options_.force_adaptation)
  LateralForceScaleEstimator force_estimator_;
  float force_scale_ = 1.f;  // the estimate
  float model_scale_ = 1.f;  // the model's (the estimate with scale_model, else 1)
  float throttle_max_configured_ = 0.f;  // options_.control_max[kThrottle] as configured
  std::vector<float> adapt_previous_, adapt_predicted_;  // nx: the last measured state, its prediction
  bool adapt_have_previous_ = false;
  double requested_speed_ = std::numeric_limits<double>::quiet_NaN();  // governs(): the host's speed
  double governed_speed_ = std::numeric_limits<double>::quiet_NaN();   // governs(): the cost's speed
};

// A controller on the CPU backend for model D and cost C.
template <Dynamics D, StageCost<D> C>
Controller make_cpu_controller(D model, C cost, const ControllerOptions& options) {
  std::string why;
  if (!options.is_valid(D::kNu, &why)) throw Error("ControllerOptions: " + why);
  auto backend = std::make_unique<CpuBackend<D, C>>(std::move(model), std::move(cost),
                                                    options.num_samples, options.horizon,
                                                    options.dt_s, options.num_threads, options.schedule);
  return Controller(std::move(backend), options);
}

}  // namespace mppi
