#pragma once
// AutoRally cost weights as data: YAML files whose keys are the AutoRallyCostParams field names
// (see data/config/autorally_cost.yaml). Missing keys keep their defaults; unknown or repeated
// keys, non-numbers, NaN, negative weights and other invalid values throw mppi::Error naming
// the file, the key and its line.
#include <string>

#include "costs/autorally_cost.hpp"

namespace mppi {

AutoRallyCostParams load_autorally_cost_params(const std::string& yaml_path);

// The same from YAML text; source_name is used in error messages in place of a file name.
AutoRallyCostParams parse_autorally_cost_params(const std::string& yaml_text,
                                                const std::string& source_name = "<yaml string>");

}  // namespace mppi
