#pragma once
// Settings of the MPPI controller. Defaults are AutoRally's (K = 1920, T = 100, 50 Hz,
// noise std 0.275 steering / 0.3 throttle, steering +-0.99, throttle [-0.99, 0.65]).
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "mppi/actuator_chain.hpp"
#include "mppi/lateral_force_adaptation.hpp"
#include "mppi/adaptive_temperature.hpp"
#include "mppi/ancillary.hpp"
#include "mppi/sampler.hpp"

namespace mppi {

// How the CPU threads share an iteration's chunks of samples (mppi/thread_schedule.hpp).
// kWorkStealing (oneTBB): idle threads steal chunks and sleep after a short spin, so a thread
// that shares its core with another process takes fewer chunks and waiting threads leave the
// cores to the working ones (measured: docs/BENCHMARKS.md, contention). kDynamic / kStatic:
// OpenMP with dynamic or static chunks. Results do not depend on it.
enum class ThreadSchedule { kWorkStealing, kDynamic, kStatic };

// Which MPPI (docs/CONTROLLER.md):
//   kPlain   plans from the measured state (the paper's).
//   kTube    Tube-MPPI (Williams et al. 2018): plans from a nominal state that follows the
//            model under the plan, and sends u = u_nom + K (x - x_nom) with the time-varying
//            LQR gains K along the plan (ancillary); the nominal state is put back on the
//            measured one when their weighted distance exceeds tube_reset_distance.
//   kRobust  Robust MPPI's choice of the nominal state (Gandhi et al. 2021): at every step the
//            measured state replaces the nominal one unless the plan costs more from it than
//            from the nominal state by more than robust_cost_margin; feedback as kTube. With
//            robust_augmented_sampling, also RMPPI's augmented sampling: every sample rolls out
//            the real system from the measured state under the feedback as well, and is
//            scored by both rollouts (AugmentedSampling in mppi/backend.hpp).
enum class ControllerVariant { kPlain, kTube, kRobust };

inline const char* variant_name(ControllerVariant v) {
  return v == ControllerVariant::kTube ? "tube" : v == ControllerVariant::kRobust ? "robust" : "plain";
}
// "plain" | "tube" | "robust"; false for anything else.
inline bool parse_controller_variant(const std::string& name, ControllerVariant* v) {
  if (name == "plain") *v = ControllerVariant::kPlain;
  else if (name == "tube") *v = ControllerVariant::kTube;
  else if (name == "robust") *v = ControllerVariant::kRobust;
  else return false;
  return true;
}

struct ControllerOptions {
  int num_samples = 1920;          // K: sampled control sequences per iteration
  int horizon = 100;               // T: time steps per sequence
  float dt_s = 0.02f;              // model time step [s] (AutoRally: 1/50 Hz)
  int iterations = 1;              // optimisation iterations per control step
  // Extra iterations at the first step after construction or reset(), when the plan is cold
  // (all zeros): the plan converges before the first command goes out. 0 = none.
  int warm_start_iterations = 0;
  float lambda = 6.0f;             // temperature of the exponential weights [cost units]
  float gamma = 0.0f;              // weight of the control cost gamma * sum_t u^T Sigma^-1 eps
  std::vector<float> noise_std = {0.275f, 0.3f};    // per control channel (diagonal Sigma)
  std::vector<float> control_min = {-0.99f, -0.99f};  // per channel clamp, lower
  std::vector<float> control_max = {0.99f, 0.65f};    // per channel clamp, upper
  std::vector<float> safe_control = {0.f, -0.5f};     // output when the state is unusable
  int smoothing_window = 0;        // Savitzky-Golay window (odd, >= 3); 0 = no smoothing
  int smoothing_order = 2;         // Savitzky-Golay polynomial order (< window)
  std::uint64_t seed = 1;          // noise seed (draws depend on seed, step, sample, t, channel)
  int num_threads = 0;             // CPU threads; 0 = OpenMP default
  ThreadSchedule schedule = ThreadSchedule::kWorkStealing;  // how the CPU threads share the work

  // How the perturbations are drawn along the horizon (mppi/sampler.hpp): white Gaussian (the
  // paper's), low-pass or derivative-space (smooth).
  SamplerOptions sampler;
  // Adaptive temperature (mppi/adaptive_temperature.hpp): with ess_share > 0, lambda is set at
  // every iteration so that the effective sample size is ess_share * K (within the tolerance
  // and the bounds); `lambda` above is then only the first step's starting guess.
  TemperatureTarget temperature;
  // The variant and its ancillary feedback (see ControllerVariant; mppi/ancillary.hpp).
  ControllerVariant variant = ControllerVariant::kPlain;
  AncillaryWeights ancillary;            // the LQR's Q, R along the plan
  float tube_reset_distance = 2.0f;      // sqrt((x - x_nom)' Q (x - x_nom)) that resets the nominal state
  float robust_cost_margin = 0.0f;       // kRobust: cost the measured state may add [cost units]
  bool robust_augmented_sampling = false;  // kRobust: RMPPI's real-system rollout in every sample
  // RMPPI's bound on a sample's real-system cost [cost units]: one real rollout the feedback
  // cannot save then costs no more than this (inf: unbounded)
  float robust_cost_bound = std::numeric_limits<float>::infinity();

  // Actuator-aware planning (mppi/actuator_chain.hpp): the delay, rate limit and lag between
  // each channel's command and the model's input; empty = the model takes the command directly.
  std::vector<ActuatorChannel> actuators;

  // Online grip adaptation (mppi/lateral_force_adaptation.hpp): the fitted scale of the model's
  // lateral tyre force sets the cost's target speed and the throttle's upper limit (the
  // controller's options().control_max follows it), and with scale_model the model's parameter
  // "lateral_force_scale" (the AutoRally network). Needs a backend that steps the model (CPU).
  LateralForceAdaptation force_adaptation;

  // Checks against a model with `num_controls` channels; on failure writes why.
  bool is_valid(int num_controls, std::string* why) const {
    auto fail = [&](const std::string& msg) {
      if (why) *why = msg;
      return false;
    };
    if (num_samples < 1) return fail("num_samples must be >= 1, got " + std::to_string(num_samples));
    if (horizon < 1) return fail("horizon must be >= 1, got " + std::to_string(horizon));
    if (!(dt_s > 0.f) || !std::isfinite(dt_s)) return fail("dt_s must be > 0");
    if (iterations < 1) return fail("iterations must be >= 1");
    if (warm_start_iterations < 0 || warm_start_iterations > 1000)
      return fail("warm_start_iterations must be in [0, 1000]");
    if (!(lambda > 0.f) || !std::isfinite(lambda)) return fail("lambda must be > 0 and finite");
    if (!(gamma >= 0.f) || !std::isfinite(gamma)) return fail("gamma must be >= 0 and finite");
    const auto n = static_cast<std::size_t>(num_controls);
    if (noise_std.size() != n || control_min.size() != n || control_max.size() != n ||
        safe_control.size() != n)
      return fail("noise_std, control_min, control_max and safe_control need " +
                  std::to_string(num_controls) + " entries (one per control channel)");
    for (std::size_t c = 0; c < n; ++c) {
      if (!(noise_std[c] > 0.f) || !std::isfinite(noise_std[c]))
        return fail("noise_std[" + std::to_string(c) + "] must be > 0 and finite");
      if (!(control_min[c] < control_max[c]))
        return fail("control_min[" + std::to_string(c) + "] must be < control_max");
      if (!(safe_control[c] >= control_min[c] && safe_control[c] <= control_max[c]))
        return fail("safe_control[" + std::to_string(c) + "] must lie within the control limits");
    }
    if (smoothing_window != 0) {
      if (smoothing_window < 3 || smoothing_window % 2 == 0)
        return fail("smoothing_window must be 0 or an odd number >= 3");
      if (smoothing_order < 0 || smoothing_order >= smoothing_window)
        return fail("smoothing_order must be in [0, smoothing_window)");
      if (smoothing_window > horizon) return fail("smoothing_window must be <= horizon");
    }
    if (num_threads < 0) return fail("num_threads must be >= 0");
    if (!sampler_is_valid(sampler, dt_s, why)) return false;
    if (temperature.ess_share != 0.f) {
      if (!(temperature.ess_share > 0.f && temperature.ess_share <= 1.f))
        return fail("temperature.ess_share must be in (0, 1] (0 = fixed temperature)");
      if (!(temperature.lambda_min > 0.f && temperature.lambda_min < temperature.lambda_max) ||
          !std::isfinite(temperature.lambda_max))
        return fail("temperature bounds need 0 < lambda_min < lambda_max < inf");
      if (!(temperature.tolerance > 0.f && temperature.tolerance < 1.f))
        return fail("temperature.tolerance must be in (0, 1)");
    }
    if (!actuators_are_valid(actuators, num_controls, dt_s, why)) return false;
    if (!force_adaptation.is_valid(why)) return false;
    if (variant != ControllerVariant::kPlain) {
      if (!actuators.empty())
        return fail("the tube and robust variants plan without an actuator chain (actuators must be empty)");
      if (!(tube_reset_distance > 0.f) || !std::isfinite(tube_reset_distance))
        return fail("tube_reset_distance must be > 0 and finite");
      if (!(robust_cost_margin >= 0.f) || !std::isfinite(robust_cost_margin))
        return fail("robust_cost_margin must be >= 0 and finite");
    }
    if (robust_augmented_sampling && variant != ControllerVariant::kRobust)
      return fail(std::string("robust_augmented_sampling needs the robust variant, got ") + variant_name(variant));
    if (!(robust_cost_bound > 0.f)) return fail("robust_cost_bound must be > 0 (inf: unbounded)");
    return true;
  }
};

}  // namespace mppi
