#include "chassis/command.hpp"

#include <cmath>

namespace mppi::chassis {

const char* to_string(CommandError error) {
  switch (error) {
    case CommandError::kNone: return "valid";
    case CommandError::kNoActuator: return "the command sets no actuator";
    case CommandError::kUnknownActuatorBits: return "the actuator mask has unknown bits";
    case CommandError::kSteeringNotFinite: return "steering is NaN or infinite";
    case CommandError::kSteeringOutOfRange: return "steering is outside [-1, 1]";
    case CommandError::kThrottleNotFinite: return "throttle is NaN or infinite";
    case CommandError::kThrottleOutOfRange: return "throttle is outside [-1, 1]";
    case CommandError::kFrontBrakeNotFinite: return "front brake is NaN or infinite";
    case CommandError::kFrontBrakeNegative: return "front brake is negative";
    case CommandError::kFrontBrakeOutOfRange: return "front brake is above 1";
  }
  return "unknown command error";
}

CommandError validate(const Command& c) {
  if ((c.actuators & actuator::kAll) == 0) return CommandError::kNoActuator;
  if ((c.actuators & ~actuator::kAll) != 0) return CommandError::kUnknownActuatorBits;
  if (c.actuators & actuator::kSteering) {
    if (!std::isfinite(c.steering)) return CommandError::kSteeringNotFinite;
    if (c.steering < -1.f || c.steering > 1.f) return CommandError::kSteeringOutOfRange;
  }
  if (c.actuators & actuator::kThrottle) {
    if (!std::isfinite(c.throttle)) return CommandError::kThrottleNotFinite;
    if (c.throttle < -1.f || c.throttle > 1.f) return CommandError::kThrottleOutOfRange;
  }
  if (c.actuators & actuator::kFrontBrake) {
    if (!std::isfinite(c.front_brake)) return CommandError::kFrontBrakeNotFinite;
    if (c.front_brake < 0.f) return CommandError::kFrontBrakeNegative;
    if (c.front_brake > 1.f) return CommandError::kFrontBrakeOutOfRange;
  }
  return CommandError::kNone;
}

}  // namespace mppi::chassis
