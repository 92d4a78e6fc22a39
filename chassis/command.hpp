#pragma once
// The chassis command (the paper's /chassisCommand): normalised actuator values, validated,
// never clamped. Frames follow the project (ISO 8855): positive steering turns LEFT, which is
// the opposite sign of AutoRally's chassisCommand (there -1 is full left); a calibration's
// `reverse` flag maps either convention onto the servo.
#include <cstdint>

namespace mppi::chassis {

// Which actuators a command sets; a controller may drive only some of them (e.g. a waypoint
// follower steers while a speed controller owns throttle and front brake).
namespace actuator {
inline constexpr std::uint8_t kSteering = 1u << 0;
inline constexpr std::uint8_t kThrottle = 1u << 1;
inline constexpr std::uint8_t kFrontBrake = 1u << 2;
inline constexpr std::uint8_t kAll = kSteering | kThrottle | kFrontBrake;
inline constexpr int kCount = 3;
}  // namespace actuator

struct Command {
  float steering = 0.f;     // [-1, 1], -1 full right, +1 full left
  float throttle = 0.f;     // [-1, 1], -1 full (rear) brake, +1 full throttle
  float front_brake = 0.f;  // [0, 1], 0 no brake, 1 full front brake
  std::uint8_t actuators = actuator::kAll;  // which of the three values this command sets
};

// Why a command was rejected. A rejected command is ignored as a whole: it never replaces the
// sender's previous command and nothing of it reaches an actuator.
enum class CommandError : std::uint8_t {
  kNone = 0,
  kNoActuator,             // actuators mask is empty
  kUnknownActuatorBits,    // actuators mask has bits beyond the three actuators
  kSteeringNotFinite,
  kSteeringOutOfRange,     // outside [-1, 1]
  kThrottleNotFinite,
  kThrottleOutOfRange,     // outside [-1, 1]
  kFrontBrakeNotFinite,
  kFrontBrakeNegative,     // < 0 (undefined in the paper)
  kFrontBrakeOutOfRange,   // > 1
};
inline constexpr int kCommandErrorCount = 10;

// Static, human-readable reason ("steering is NaN or infinite", ...).
const char* to_string(CommandError error);

// kNone when every actuator the command sets holds a valid value (unset ones are not looked at).
CommandError validate(const Command& command);

}  // namespace mppi::chassis
