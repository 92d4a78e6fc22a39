// YAML -> AutoRallyCostParams, strict: every mistake is an error with file:line.
#include "costs/cost_config.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "mppi/error.hpp"
#include "mppi/yaml_number.hpp"

namespace mppi {

namespace {

using FloatField = float AutoRallyCostParams::*;

// The YAML key of every field (= its C++ name).
const std::pair<const char*, FloatField> kFields[] = {
    {"track_weight", &AutoRallyCostParams::track_weight},
    {"speed_weight", &AutoRallyCostParams::speed_weight},
    {"crash_weight", &AutoRallyCostParams::crash_weight},
    {"slip_weight", &AutoRallyCostParams::slip_weight},
    {"target_speed_mps", &AutoRallyCostParams::target_speed_mps},
    {"crash_discount", &AutoRallyCostParams::crash_discount},
    {"boundary_threshold", &AutoRallyCostParams::boundary_threshold},
    {"max_roll_rad", &AutoRallyCostParams::max_roll_rad},
    {"max_yaw_rate_radps", &AutoRallyCostParams::max_yaw_rate_radps},
    {"slip_min_speed_mps", &AutoRallyCostParams::slip_min_speed_mps},
};

// "file:line:column" (1-based) of a node, or just "file" when yaml-cpp has no position.
std::string where(const std::string& source, const YAML::Mark& mark) { return yaml_where(source, mark); }

std::string known_keys() {
  std::string out;
  for (const auto& [name, field] : kFields) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

AutoRallyCostParams from_node(const YAML::Node& root, const std::string& source) {
  AutoRallyCostParams params;
  if (!root.IsDefined() || root.IsNull()) return params;  // empty document: all defaults
  if (!root.IsMap())
    throw Error(where(source, root.Mark()) + ": AutoRally cost parameters must be a mapping of key: number");
  std::set<std::string> seen;
  for (const auto& item : root) {
    const YAML::Node& key_node = item.first;
    const YAML::Node& value = item.second;
    const std::string key = key_node.IsScalar() ? key_node.Scalar() : std::string("<non-scalar key>");
    const std::string at = where(source, key_node.Mark());
    FloatField field = nullptr;
    for (const auto& [name, f] : kFields)
      if (key == name) field = f;
    if (!field)
      throw Error(at + ": unknown key '" + key + "' in AutoRally cost parameters (known: " + known_keys() + ")");
    if (!seen.insert(key).second) throw Error(at + ": key '" + key + "' given twice");
    const double v = yaml_number(value, key, source, /*allow_infinite=*/true);
    params.*field = static_cast<float>(v);
    std::string why;
    // Check each value where it is read so that the message can point at its line.
    AutoRallyCostParams single;  // defaults are valid; change only this field
    single.*field = params.*field;
    if (!single.is_valid(&why)) throw Error(where(source, value.Mark()) + ": key '" + key + "': " + why);
  }
  std::string why;
  if (!params.is_valid(&why)) throw Error(source + ": invalid AutoRally cost parameters: " + why);
  return params;
}

}  // namespace

AutoRallyCostParams parse_autorally_cost_params(const std::string& yaml_text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw Error(where(source_name, e.mark) + ": YAML syntax error: " + e.msg);
  }
  return from_node(root, source_name);
}

AutoRallyCostParams load_autorally_cost_params(const std::string& yaml_path) {
  std::ifstream in(yaml_path);
  if (!in) throw Error(yaml_path + ": cannot open AutoRally cost parameter file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_autorally_cost_params(buffer.str(), yaml_path);
}

}  // namespace mppi
