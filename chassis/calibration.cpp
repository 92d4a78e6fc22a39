#include "chassis/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "base/error.hpp"
#include "chassis/yaml_util.hpp"

namespace mppi::chassis {

bool ActuatorCalibration::is_valid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  for (double p : {min_us, center_us, max_us})
    if (!std::isfinite(p) || p < 500.0 || p > 2500.0)
      return fail("pulse widths must lie in [500, 2500] us");
  if (!(min_us <= center_us && center_us <= max_us))
    return fail("pulse widths must satisfy min <= center <= max");
  if (!(min_us < max_us)) return fail("min must be < max");
  return true;
}

double ActuatorCalibration::pulse_us(double v) const {
  if (std::isnan(v)) return center_us;
  if (reverse) v = -v;
  v = std::clamp(v, -1.0, 1.0);
  const double p = v >= 0.0 ? center_us + (max_us - center_us) * v
                            : center_us + (center_us - min_us) * v;
  return std::clamp(p, min_us, max_us);  // guard: never outside [min, max]
}

double ActuatorCalibration::value(double p) const {
  if (std::isnan(p)) return 0.0;
  p = std::clamp(p, min_us, max_us);
  double v = 0.0;
  if (p > center_us) v = (p - center_us) / (max_us - center_us);
  else if (p < center_us) v = (p - center_us) / (center_us - min_us);
  return reverse ? -v : v;
}

PulseWidths PulseWidths::rounded() const {
  return {std::round(steering_us), std::round(throttle_us), std::round(front_brake_us)};
}

bool Calibration::is_valid(std::string* why) const {
  std::string w;
  if (!steering.is_valid(&w)) {
    if (why) *why = "steering: " + w;
    return false;
  }
  if (!throttle.is_valid(&w)) {
    if (why) *why = "throttle: " + w;
    return false;
  }
  if (!front_brake.is_valid(&w)) {
    if (why) *why = "frontBrake: " + w;
    return false;
  }
  // Steering and throttle act both ways; the front brake only needs its braking side.
  if (!(steering.min_us < steering.center_us && steering.center_us < steering.max_us)) {
    if (why) *why = "steering: center must lie strictly between min and max";
    return false;
  }
  if (!(throttle.min_us < throttle.center_us && throttle.center_us < throttle.max_us)) {
    if (why) *why = "throttle: center must lie strictly between min and max";
    return false;
  }
  const bool brake_side_ok = front_brake.reverse ? front_brake.min_us < front_brake.center_us
                                                 : front_brake.center_us < front_brake.max_us;
  if (!brake_side_ok) {
    if (why) *why = "frontBrake: no pulse range on the braking side of center";
    return false;
  }
  return true;
}

PulseWidths Calibration::pulses(const Command& c) const {
  return {steering.pulse_us(c.steering), throttle.pulse_us(c.throttle),
          front_brake.pulse_us(c.front_brake)};
}

Command Calibration::values(const PulseWidths& p) const {
  Command c;
  c.steering = static_cast<float>(steering.value(p.steering_us));
  c.throttle = static_cast<float>(throttle.value(p.throttle_us));
  c.front_brake = static_cast<float>(front_brake.value(p.front_brake_us));
  c.actuators = actuator::kAll;
  return c;
}

namespace {
ActuatorCalibration parse_actuator(const YAML::Node& node, const std::string& name,
                                   const std::string& source, bool name_allowed) {
  using namespace detail;
  if (!node.IsMap()) throw Error(where(source, node) + ": actuator '" + name + "' must be a map");
  ActuatorCalibration a;
  bool has[4] = {};
  for (const auto& kv : node) {
    const std::string key = detail::text(kv.first, "a key of actuator '" + name + "'", source);
    if (key == "min") a.min_us = number(kv.second, key, source), has[0] = true;
    else if (key == "center") a.center_us = number(kv.second, key, source), has[1] = true;
    else if (key == "max") a.max_us = number(kv.second, key, source), has[2] = true;
    else if (key == "reverse") a.reverse = boolean(kv.second, key, source), has[3] = true;
    else if (!(name_allowed && key == "name"))
      throw Error(where(source, kv.first) + ": unknown key '" + key + "' in actuator '" + name +
                  "' (valid: min, center, max, reverse)");
  }
  const char* keys[4] = {"min", "center", "max", "reverse"};
  for (int i = 0; i < 4; ++i)
    if (!has[i])
      throw Error(where(source, node) + ": actuator '" + name + "' lacks '" + keys[i] + "'");
  std::string why;
  if (!a.is_valid(&why)) throw Error(where(source, node) + ": actuator '" + name + "': " + why);
  return a;
}
}  // namespace

Calibration Calibration::parse_yaml(const std::string& text, const std::string& source) {
  using namespace detail;
  const YAML::Node root = load_document(text, source);
  if (!root.IsMap()) throw Error(source + ": a chassis calibration must be a YAML map");
  std::map<std::string, ActuatorCalibration> found;
  for (const auto& kv : root) {
    std::string name = detail::text(kv.first, "an actuator name", source);
    bool indexed = false;
    if (kv.second.IsMap() && kv.second["name"]) {  // '0': {name: 'steering', ...}
      name = detail::text(kv.second["name"], "an actuator name", source);
      indexed = true;
    }
    if (name != "steering" && name != "throttle" && name != "frontBrake")
      throw Error(where(source, kv.first) + ": unknown actuator '" + name +
                  "' (valid: steering, throttle, frontBrake)");
    if (found.count(name)) throw Error(where(source, kv.first) + ": actuator '" + name + "' twice");
    found[name] = parse_actuator(kv.second, name, source, indexed);
  }
  for (const char* need : {"steering", "throttle", "frontBrake"})
    if (!found.count(need)) throw Error(source + ": missing actuator '" + std::string(need) + "'");
  Calibration c;
  c.steering = found["steering"];
  c.throttle = found["throttle"];
  c.front_brake = found["frontBrake"];
  std::string why;
  if (!c.is_valid(&why)) throw Error(source + ": " + why);
  return c;
}

Calibration Calibration::load_yaml(const std::string& path) {
  return parse_yaml(detail::read_text_file(path), path);
}

}  // namespace mppi::chassis
