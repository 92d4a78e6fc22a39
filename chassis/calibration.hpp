#pragma once
// Chassis calibration (the paper's "calibration layer above the PWM signal"): per actuator the
// minimum, center and maximum servo pulse width in microseconds and whether the servo is
// reversed. A normalised value v maps linearly center -> max for v in [0, 1] and center -> min
// for v in [-1, 0], so a value means the same on every calibrated vehicle and the pulse width
// never leaves [min, max]. Loaded from AutoRally's YAML (arChassisConfig_<chassis>.yaml).
#include <string>

#include "chassis/command.hpp"

namespace mppi::chassis {

struct ActuatorCalibration {
  double min_us = 1000.0;     // pulse width at -1 (0 for the front brake: min may equal center)
  double center_us = 1500.0;  // pulse width at 0 (neutral: straight ahead, no throttle, no brake)
  double max_us = 2000.0;     // pulse width at +1
  bool reverse = false;       // servo mounted the other way round: v is negated before mapping

  // min <= center <= max, min < max, all within [500, 2500] us (hobby servo range).
  bool is_valid(std::string* why) const;
  // Pulse width for v; v outside [-1, 1] or NaN (never produced by a validated command) gives
  // the nearest end or the center, so the result is always within [min, max].
  double pulse_us(double v) const;
  // The normalised value a pulse width stands for (inverse of pulse_us on [min, max]).
  double value(double pulse_us) const;
};

// Pulse widths of the three actuators [us]; doubles so that a simulator sees the command
// exactly (a real link rounds them to whole microseconds: `rounded()`).
struct PulseWidths {
  double steering_us = 0.0;
  double throttle_us = 0.0;
  double front_brake_us = 0.0;
  PulseWidths rounded() const;
};

struct Calibration {
  ActuatorCalibration steering;                               // AutoRally default
  ActuatorCalibration throttle;                               // AutoRally default
  ActuatorCalibration front_brake{1500.0, 1500.0, 2000.0, false};  // brake only pulls one way

  bool is_valid(std::string* why) const;
  // Pulse widths of a command's three values (the mask is not looked at).
  PulseWidths pulses(const Command& command) const;
  // Normalised values of three pulse widths (mask: all actuators).
  Command values(const PulseWidths& pulses) const;
  // Pulse widths of all actuators at neutral (steering center, throttle center, no brake).
  PulseWidths neutral() const { return pulses(Command{}); }

  // Reads AutoRally's format: a map keyed by actuator name
  //   steering: {center: 1500, min: 1000, max: 2000, reverse: false}
  // or the older one keyed by index with a name field
  //   '0': {name: 'steering', center: 1500, min: 1000, max: 2000, reverse: false}
  // with the actuators steering, throttle and frontBrake (all three required). Throws
  // mppi::Error naming file:line:column and key on anything else.
  static Calibration load_yaml(const std::string& path);
  static Calibration parse_yaml(const std::string& text, const std::string& source);
};

}  // namespace mppi::chassis
