#pragma once
// The simulated car: any vehicle model integrated at a fixed high rate (500 Hz by default),
// behind actuators with rate limits (a servo cannot jump from full left to full right, and
// the throttle channel has its own slew limit), each optionally after a pure transport delay.
// Commands are clamped to the actuator range.
#include <algorithm>
#include <cmath>
#include <vector>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "mppi/concepts.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi::sim {

struct ActuatorLimits {
  float steer_rate_per_s = 5.0f;     // max |d steer / dt| [1/s]: full lock to lock (2) in 0.4 s
  float throttle_rate_per_s = 10.0f; // max |d throttle / dt| [1/s]
  float steer_min = -1.f, steer_max = 1.f;
  float throttle_min = -1.f, throttle_max = 1.f;
  // Pure transport delay of each command [s] (rounded to the integration step): the actuator
  // acts on the command given this long before. Before any command: at rest (0).
  float steer_delay_s = 0.f, throttle_delay_s = 0.f;
};

template <VehicleDynamics D>
class Plant {
 public:
  explicit Plant(D model, ActuatorLimits limits = {}, float dt_s = 0.002f)
      : model_(std::move(model)), limits_(limits), dt_s_(dt_s),
        scratch_(std::max<std::size_t>(1, model_.scratch_floats(1))) {
    if (!(dt_s > 0.f)) throw Error("Plant: integration step must be > 0");
    if (!(limits.steer_delay_s >= 0.f && limits.throttle_delay_s >= 0.f && limits.steer_delay_s < 10.f &&
          limits.throttle_delay_s < 10.f))
      throw Error("Plant: command delays must be in [0, 10) s");
    steer_delay_steps_ = static_cast<std::size_t>(std::lround(limits.steer_delay_s / dt_s));
    throttle_delay_steps_ = static_cast<std::size_t>(std::lround(limits.throttle_delay_s / dt_s));
    issued_.assign(std::max(steer_delay_steps_, throttle_delay_steps_) + 1, Control{});
  }

  void reset(const VehicleState& s) {
    model_.init_state(s, x_);
    applied_ = Control{};
    std::fill(issued_.begin(), issued_.end(), Control{});
    time_s_ = 0.0;
  }
  // Set the full model state (e.g. to restore a snapshot).
  void set_state(const float* x) { std::copy(x, x + D::kNx, x_); }

  // Hold `command` for duration_s, integrating at dt_s with actuator slew limits.
  void advance(const Control& command, float duration_s) {
    const int substeps = std::max(1, static_cast<int>(std::lround(duration_s / dt_s_)));
    const float steer_target = std::clamp(command.steer, limits_.steer_min, limits_.steer_max);
    const float throttle_target =
        std::clamp(command.throttle, limits_.throttle_min, limits_.throttle_max);
    for (int i = 0; i < substeps; ++i) {
      // The commands issued steps ago (a ring of the last max-delay + 1 steps).
      head_ = (head_ + 1) % issued_.size();
      issued_[head_] = Control{steer_target, throttle_target};
      const std::size_t n = issued_.size();
      const float steer_in = issued_[(head_ + n - steer_delay_steps_) % n].steer;
      const float throttle_in = issued_[(head_ + n - throttle_delay_steps_) % n].throttle;
      applied_.steer = slew(applied_.steer, steer_in, limits_.steer_rate_per_s * dt_s_);
      applied_.throttle = slew(applied_.throttle, throttle_in, limits_.throttle_rate_per_s * dt_s_);
      float u[D::kNu] = {};
      u[control::kSteer] = applied_.steer;
      u[control::kThrottle] = applied_.throttle;
      model_.template step<1>(Batch<D::kNx, 1>{x_}, ConstBatch<D::kNu, 1>{u}, dt_s_, scratch_.data());
      time_s_ += dt_s_;
    }
  }

  const float* state() const { return x_; }
  VehicleState vehicle_state() const { return VehicleState::from_array(x_); }
  Control applied() const { return applied_; }
  double time_s() const { return time_s_; }
  float dt_s() const { return dt_s_; }
  const D& model() const { return model_; }

 private:
  static float slew(float current, float target, float max_delta) {
    return current + std::clamp(target - current, -max_delta, max_delta);
  }

  D model_;
  ActuatorLimits limits_;
  float dt_s_;
  std::vector<float> scratch_;
  float x_[D::kNx] = {};
  Control applied_;
  double time_s_ = 0.0;
  std::vector<Control> issued_;  // ring of the commands of the last steps, for the delays
  std::size_t head_ = 0;
  std::size_t steer_delay_steps_ = 0, throttle_delay_steps_ = 0;
};

}  // namespace mppi::sim
