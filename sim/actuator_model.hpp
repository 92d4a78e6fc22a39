#pragma once
// The actuator chain a controller plans through (ControllerOptions::actuators,
// mppi/actuator_chain.hpp), read from what describes the car's actuators:
//   "none" or ""  no chain: the model takes the command directly;
//   "plant"       the simulated car's own actuators: its rate limits and pure delays
//                 (ActuatorLimits) and, for a corrected-model plant, the file's actuator
//                 effects (steer/throttle delay, lag and slew);
//   FILE          a corrected-model file (as `mppi-fit diagnose` writes): its actuator effects.
// Delays add, a slew of T seconds per unit is a rate limit of 1 / T per second (the tighter of
// two limits holds), and a lag is the effect's time constant.
#include <string>
#include <vector>

#include "mppi/actuator_chain.hpp"
#include "sim/plant.hpp"

namespace mppi {
struct EffectParams;
}

namespace mppi::sim {

// Channels (steer, throttle) from a corrected model's effects, after the plant's limits.
std::vector<ActuatorChannel> actuator_channels(const ActuatorLimits& limits, const EffectParams* effects);

// The chain named by `source` (see above) for a run whose plant is `plant` with data file
// `plant_params_yaml` and actuator limits `limits`. Throws mppi::Error naming the source if it
// cannot be read.
std::vector<ActuatorChannel> resolve_actuator_model(const std::string& source, const std::string& plant,
                                                    const std::string& plant_params_yaml,
                                                    const ActuatorLimits& limits);

}  // namespace mppi::sim
