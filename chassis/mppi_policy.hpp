#pragma once
// MPPI as a control-loop policy: the controller's first control becomes a chassis command
// (steering, throttle; no front brake). The controller never returns NaN (it returns its safe
// control instead), and its clamp keeps the values inside [-1, 1].
#include <span>

#include "chassis/command.hpp"
#include "mppi/controller.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi::chassis {

inline Command command_from_control(float steer, float throttle) {
  return Command{steer, throttle, 0.f, actuator::kAll};
}

// `observe` maps the state the loop reads to the controller model's state (identity if the
// sizes match). The returned policy keeps references to controller; single-threaded use.
template <class Observe>
auto mppi_policy(Controller& controller, Observe observe, std::vector<float>& model_state) {
  return [&controller, observe, &model_state](std::span<const float> x) {
    observe(x, std::span<float>(model_state));
    const auto u = controller.step(model_state);
    return command_from_control(u[control::kSteer], u[control::kThrottle]);
  };
}

}  // namespace mppi::chassis
