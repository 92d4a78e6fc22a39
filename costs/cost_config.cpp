// YAML -> AutoRallyCostParams through the cost's parameter table (costs/autorally_cost.hpp),
// strict: every mistake is an error with file:line.
#include "costs/cost_config.hpp"

#include "base/error.hpp"
#include "base/param_yaml.hpp"

namespace mppi {

AutoRallyCostParams parse_autorally_cost_params(const std::string& yaml_text, const std::string& source_name) {
  AutoRallyCostParams params;
  read_param_yaml(param_table(params), yaml_text, source_name, "AutoRally cost parameters");
  std::string why;
  if (!params.is_valid(&why)) throw Error(source_name + ": invalid AutoRally cost parameters: " + why);
  return params;
}

AutoRallyCostParams load_autorally_cost_params(const std::string& yaml_path) {
  return parse_autorally_cost_params(read_text_file(yaml_path, "AutoRally cost parameter"), yaml_path);
}

}  // namespace mppi
