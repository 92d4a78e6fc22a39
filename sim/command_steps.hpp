#pragma once
// How much the commands sent to the car change from one control step to the next: the mean of
// |u_k - u_{k-1}| per channel over a run's consecutive control steps (a measure of chatter; a
// smooth controller sends small steps).
#include <cmath>
#include <optional>

#include "mppi/vehicle_state.hpp"

namespace mppi::sim {

class CommandSteps {
 public:
  // The command of the next control step.
  void add(const Control& command) {
    if (previous_) {
      steer_sum_ += std::abs(static_cast<double>(command.steer) - previous_->steer);
      throttle_sum_ += std::abs(static_cast<double>(command.throttle) - previous_->throttle);
      ++steps_;
    }
    previous_ = command;
  }
  // Means per control step; 0 with fewer than two commands.
  double mean_abs_steer_step() const { return steps_ ? steer_sum_ / steps_ : 0.0; }
  double mean_abs_throttle_step() const { return steps_ ? throttle_sum_ / steps_ : 0.0; }

 private:
  std::optional<Control> previous_;
  double steer_sum_ = 0.0, throttle_sum_ = 0.0;
  long steps_ = 0;
};

}  // namespace mppi::sim
