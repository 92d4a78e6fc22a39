#pragma once
// Shared pieces of the strict YAML settings readers (costs/cost_config.cpp,
// dynamics/vehicle_params_io.cpp): where a node is, and a number that must be one.
#include <string>

namespace YAML {
class Mark;
class Node;
}  // namespace YAML

namespace mppi {

// "file:line:column" (1-based) of a YAML position, or just "file" when it has none.
std::string yaml_where(const std::string& source, const YAML::Mark& mark);

// The scalar `value` of `key` as a number. Throws mppi::Error with file:line:column if it is not
// a scalar, not a number, NaN, or (unless allow_infinite) infinite.
double yaml_number(const YAML::Node& value, const std::string& key, const std::string& source,
                   bool allow_infinite = false);

// The scalar `value` as text (a key or a name). Throws mppi::Error with file:line:column if it
// is a map, a list or null; `what` names it in the message ("key", "nominal").
std::string yaml_text(const YAML::Node& value, const std::string& what, const std::string& source);

}  // namespace mppi
