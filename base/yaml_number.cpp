#include "base/yaml_number.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>

#include "base/error.hpp"

namespace mppi {

std::string yaml_where(const std::string& source, const YAML::Mark& mark) {
  if (mark.is_null()) return source;
  return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

double yaml_number(const YAML::Node& value, const std::string& key, const std::string& source,
                   bool allow_infinite) {
  const std::string at = yaml_where(source, value.Mark());
  if (!value.IsScalar()) throw Error(at + ": key '" + key + "' must be a number");
  double v = 0.0;
  try {
    v = value.as<double>();
  } catch (const YAML::Exception&) {
    throw Error(at + ": key '" + key + "' must be a number, got '" + value.Scalar() + "'");
  }
  if (std::isnan(v)) throw Error(at + ": key '" + key + "' is NaN");
  if (!allow_infinite && !std::isfinite(v)) throw Error(at + ": key '" + key + "' must be finite");
  return v;
}

std::string yaml_text(const YAML::Node& value, const std::string& what, const std::string& source) {
  if (!value.IsScalar()) throw Error(yaml_where(source, value.Mark()) + ": " + what + " must be a plain text value");
  return value.Scalar();
}

}  // namespace mppi
