#include "sysid/rosbag/bag_topic_map.hpp"

#include <cmath>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "base/error.hpp"

namespace mppi::sysid::bag {

namespace {
double number(const std::string& key, const std::string& value, const std::string& where) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value.size() || !std::isfinite(v))
    throw Error(where + ": topic map key '" + key + "': not a number: '" + value + "'");
  return v;
}
std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}
}  // namespace

std::vector<std::string> topic_map_keys() {
  return {"pose",     "chassis_state", "command",        "wheel_speeds",       "controls", "twist_frame",
          "steer_sign", "rate_hz",     "max_pose_gap_s", "max_command_age_s", "command_lead_s", "vehicle"};
}

void BagTopicMap::set(const std::string& key, const std::string& value, const std::string& where) {
  if (key == "pose") pose = value;
  else if (key == "chassis_state") chassis_state = value;
  else if (key == "command") command = value;
  else if (key == "wheel_speeds") wheel_speeds = value;
  else if (key == "vehicle") vehicle = value;
  else if (key == "controls") {
    if (value != "auto" && value != "state" && value != "command")
      throw Error(where + ": topic map key 'controls': expected auto, state or command, got '" + value + "'");
    controls = value;
  } else if (key == "twist_frame") {
    if (value != "world" && value != "body")
      throw Error(where + ": topic map key 'twist_frame': expected world or body, got '" + value + "'");
    twist_frame = value;
  } else if (key == "steer_sign") {
    const double v = number(key, value, where);
    if (v != 1 && v != -1) throw Error(where + ": topic map key 'steer_sign': expected 1 or -1, got '" + value + "'");
    steer_sign = v;
  } else if (key == "rate_hz" || key == "max_pose_gap_s" || key == "max_command_age_s") {
    const double v = number(key, value, where);
    if (v < 0 || (key != "rate_hz" && v == 0))
      throw Error(where + ": topic map key '" + key + "': expected a positive number" +
                  (key == "rate_hz" ? " (or 0: the pose rate)" : "") + ", got '" + value + "'");
    (key == "rate_hz" ? rate_hz : key == "max_pose_gap_s" ? max_pose_gap_s : max_command_age_s) = v;
  } else if (key == "command_lead_s") {
    const double v = number(key, value, where);
    if (!(v >= 0 && v < 1))
      throw Error(where + ": topic map key 'command_lead_s': expected a number in [0, 1), got '" + value + "'");
    command_lead_s = v;
  } else {
    std::string known;
    for (const auto& k : topic_map_keys()) known += (known.empty() ? "" : ", ") + k;
    throw Error(where + ": unknown topic map key '" + key + "' (known: " + known + ")");
  }
}

void BagTopicMap::apply_pairs(const std::string& text) {
  std::istringstream in(text);
  std::string pair;
  while (std::getline(in, pair, ',')) {
    pair = trimmed(pair);
    if (pair.empty()) continue;
    const auto eq = pair.find('=');
    if (eq == std::string::npos) throw Error("--topic: expected KEY=VALUE, got '" + pair + "'");
    set(trimmed(pair.substr(0, eq)), trimmed(pair.substr(eq + 1)), "--topic");
  }
}

void BagTopicMap::apply_yaml_file(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw Error(path + ": cannot read the topic map");
  } catch (const YAML::Exception& e) {
    throw Error(path + ":" + std::to_string(e.mark.line + 1) + ": not YAML: " + e.msg);
  }
  if (root.IsNull()) return;
  if (!root.IsMap()) throw Error(path + ": the topic map must be a mapping of KEY: VALUE");
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (!kv.second.IsScalar())
      throw Error(path + ":" + std::to_string(kv.second.Mark().line + 1) + ": key '" + key + "' needs a single value");
    set(key, kv.second.as<std::string>(), path + ":" + std::to_string(kv.first.Mark().line + 1));
  }
}

std::string BagTopicMap::describe() const {
  std::ostringstream o;
  o << "pose=" << pose << ",chassis_state=" << chassis_state << ",command=" << command
    << ",wheel_speeds=" << wheel_speeds << ",controls=" << controls << ",twist_frame=" << twist_frame
    << ",steer_sign=" << steer_sign;
  if (command_lead_s > 0) o << ",command_lead_s=" << command_lead_s;
  return o.str();
}

}  // namespace mppi::sysid::bag
