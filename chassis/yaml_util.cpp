#include "chassis/yaml_util.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "base/error.hpp"

namespace mppi::chassis::detail {

std::string where(const std::string& source, const YAML::Node& node) {
  const YAML::Mark m = node.Mark();
  if (m.is_null()) return source;
  return source + ":" + std::to_string(m.line + 1) + ":" + std::to_string(m.column + 1);
}

YAML::Node load_document(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(source + ":" + std::to_string(e.mark.line + 1) + ":" +
                std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  }
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

double number(const YAML::Node& node, const std::string& key, const std::string& source) {
  if (!node.IsScalar())
    throw Error(where(source, node) + ": '" + key + "' must be a number");
  const std::string s = node.Scalar();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v))
    throw Error(where(source, node) + ": '" + key + "' must be a finite number, got '" + s + "'");
  return v;
}

std::string text(const YAML::Node& node, const std::string& what, const std::string& source) {
  if (!node.IsScalar()) throw Error(where(source, node) + ": " + what + " must be a plain text value");
  return node.Scalar();
}

long integer(const YAML::Node& node, const std::string& key, const std::string& source) {
  if (!node.IsScalar()) throw Error(where(source, node) + ": '" + key + "' must be an integer");
  const std::string s = node.Scalar();
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE)
    throw Error(where(source, node) + ": '" + key + "' must be an integer, got '" + s + "'");
  return v;
}

bool boolean(const YAML::Node& node, const std::string& key, const std::string& source) {
  if (!node.IsScalar()) throw Error(where(source, node) + ": '" + key + "' must be true or false");
  const std::string& s = node.Scalar();
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  throw Error(where(source, node) + ": '" + key + "' must be true or false, got '" + s + "'");
}

}  // namespace mppi::chassis::detail
