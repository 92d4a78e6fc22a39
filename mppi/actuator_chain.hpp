#pragma once
// The actuators between the controller's command and the model's input, per channel: a pure
// delay, then a rate limit, then a first-order lag (a servo behind a slewing driver):
//   cmd_t  = the command sent delay_steps control steps ago
//   r_t    = r_{t-1} + clamp(cmd_t - r_{t-1}, -max_change, max_change)
//   a_t    = a_{t-1} + lag_alpha (r_t - a_{t-1}),   lag_alpha = 1 - exp(-dt / lag_s)
// The model sees a_t. The controller carries the chain's state (the commands sent but not yet
// acting, r and a) and every rollout starts from it, so a model that holds no command history
// (the AutoRally network) plans with the actuators it will really meet: the first delay_steps
// inputs of each rollout are the commands already sent, and the sampled sequence is what the
// controller sends.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace mppi {

// One channel's actuator, in seconds (0 = none).
struct ActuatorChannel {
  float delay_s = 0.f;     // pure transport delay
  float lag_s = 0.f;       // first-order time constant
  float rate_per_s = 0.f;  // max |d input / dt| [1/s]; 0 = unlimited
};

inline constexpr int kMaxActuatorChannels = 8;
inline constexpr int kMaxActuatorDelaySteps = 32;

// A channel in control steps of dt_s.
struct ActuatorStep {
  int delay_steps = 0;
  float lag_alpha = 1.f;  // 1: no lag
  float max_change = std::numeric_limits<float>::infinity();
};

inline ActuatorStep actuator_step(const ActuatorChannel& c, float dt_s) {
  ActuatorStep s;
  s.delay_steps = static_cast<int>(std::lround(c.delay_s / dt_s));
  s.lag_alpha = c.lag_s > 0.f ? 1.f - std::exp(-dt_s / c.lag_s) : 1.f;
  s.max_change = c.rate_per_s > 0.f ? c.rate_per_s * dt_s : std::numeric_limits<float>::infinity();
  return s;
}

// The chain's state at the start of a control step, per channel.
struct ActuatorState {
  float pending[kMaxActuatorChannels][kMaxActuatorDelaySteps] = {};  // oldest first
  float rate_out[kMaxActuatorChannels] = {};
  float lag_out[kMaxActuatorChannels] = {};
};

// The chain as the rollouts see it: nullptr steps = no actuator model.
struct ActuatorPlan {
  const ActuatorStep* steps = nullptr;  // nu
  const ActuatorState* start = nullptr;
  bool enabled() const { return steps != nullptr; }
};

// Checks `channels` (empty = off, else one per control channel) for control period dt_s.
inline bool actuators_are_valid(const std::vector<ActuatorChannel>& channels, int num_controls,
                                float dt_s, std::string* why) {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (channels.empty()) return true;
  if (static_cast<int>(channels.size()) != num_controls)
    return fail("actuators need " + std::to_string(num_controls) + " entries (one per control channel), got " +
                std::to_string(channels.size()));
  if (num_controls > kMaxActuatorChannels) return fail("actuators: at most 8 control channels");
  for (std::size_t c = 0; c < channels.size(); ++c) {
    const ActuatorChannel& a = channels[c];
    const std::string at = "actuators[" + std::to_string(c) + "]";
    if (!(a.delay_s >= 0.f) || !std::isfinite(a.delay_s) ||
        std::lround(a.delay_s / dt_s) >= kMaxActuatorDelaySteps)
      return fail(at + ".delay_s must be in [0, " + std::to_string((kMaxActuatorDelaySteps - 0.5) * dt_s) +
                  ") s, got " + std::to_string(a.delay_s));
    if (!(a.lag_s >= 0.f) || !std::isfinite(a.lag_s)) return fail(at + ".lag_s must be >= 0 and finite");
    if (!(a.rate_per_s >= 0.f) || !std::isfinite(a.rate_per_s))
      return fail(at + ".rate_per_s must be >= 0 (0 = unlimited) and finite");
  }
  return true;
}

namespace detail {
// The inputs the model sees at step t for W lanes: u[c * W + j]. Commands of the lanes at step
// s: cmd(s)[c * chan_stride + j] = v + s * step_stride; rate and lag hold the chain's state per
// lane (nu x W), set from plan.start at t = 0.
template <int W>
inline void actuator_inputs(const ActuatorPlan& plan, int nu, int t, const float* v,
                            std::size_t chan_stride, std::size_t step_stride, float* rate,
                            float* lag, float* u) noexcept {
  for (int c = 0; c < nu; ++c) {
    const ActuatorStep& s = plan.steps[c];
    float* rc = rate + c * W;
    float* lc = lag + c * W;
    float* uc = u + c * W;
    if (t == 0) {
      std::fill_n(rc, W, plan.start->rate_out[c]);
      std::fill_n(lc, W, plan.start->lag_out[c]);
    }
    const float m = s.max_change, alpha = s.lag_alpha;
    if (t < s.delay_steps) {
      const float cmd = plan.start->pending[c][t];
      for (int j = 0; j < W; ++j) {
        const float r = rc[j] + std::clamp(cmd - rc[j], -m, m);
        rc[j] = r;
        uc[j] = lc[j] = lc[j] + alpha * (r - lc[j]);
      }
    } else {
      const float* cmd = v + static_cast<std::size_t>(t - s.delay_steps) * step_stride +
                         static_cast<std::size_t>(c) * chan_stride;
      for (int j = 0; j < W; ++j) {
        const float r = rc[j] + std::clamp(cmd[j] - rc[j], -m, m);
        rc[j] = r;
        uc[j] = lc[j] = lc[j] + alpha * (r - lc[j]);
      }
    }
  }
}
}  // namespace detail

// Advances the carried state by one control step in which `command` (nu) was sent: the same
// arithmetic as a rollout's first step.
inline void advance_actuators(const ActuatorStep* steps, int nu, const float* command,
                              ActuatorState& s) noexcept {
  for (int c = 0; c < nu; ++c) {
    const int d = steps[c].delay_steps;
    float cmd = command[c];
    if (d > 0) {
      const float oldest = s.pending[c][0];
      std::copy(s.pending[c] + 1, s.pending[c] + d, s.pending[c]);
      s.pending[c][d - 1] = cmd;
      cmd = oldest;
    }
    const float m = steps[c].max_change, alpha = steps[c].lag_alpha;
    const float r = s.rate_out[c] + std::clamp(cmd - s.rate_out[c], -m, m);
    s.rate_out[c] = r;
    s.lag_out[c] = s.lag_out[c] + alpha * (r - s.lag_out[c]);
  }
}

}  // namespace mppi
