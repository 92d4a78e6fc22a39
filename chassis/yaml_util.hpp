#pragma once
// Small strict YAML helpers of the chassis loaders (file:line:column in every message).
#include <yaml-cpp/yaml.h>

#include <string>

namespace mppi::chassis::detail {

std::string where(const std::string& source, const YAML::Node& node);
// Loads a YAML document from text; throws mppi::Error with the parser's position.
YAML::Node load_document(const std::string& text, const std::string& source);
// Reads a whole file; throws mppi::Error if it cannot be read.
std::string read_text_file(const std::string& path);
double number(const YAML::Node& node, const std::string& key, const std::string& source);
// A scalar as text (a key or a name); throws mppi::Error with file:line:column for a map, a
// list or null. `what` names it in the message.
std::string text(const YAML::Node& node, const std::string& what, const std::string& source);
long integer(const YAML::Node& node, const std::string& key, const std::string& source);
bool boolean(const YAML::Node& node, const std::string& key, const std::string& source);

}  // namespace mppi::chassis::detail
