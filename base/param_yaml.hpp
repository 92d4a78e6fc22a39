#pragma once
// YAML <-> parameter tables (base/param_table.hpp), strict: an unknown or repeated key, a value
// that is not a finite number, or one out of its range throws mppi::Error naming the source
// (file), line and key. Keys "outer.inner" of a table are read from and written to a nested
// map `outer: {inner: ..}`.
#include <string>
#include <vector>

#include "base/param_table.hpp"

namespace YAML {
class Node;
}

namespace mppi {

// Reads `text` into the values the fields point at. Keys not in the text keep their values.
// `what` names the parameter set in messages ("single-track parameters").
void read_param_yaml(const std::vector<ParamField>& fields, const std::string& text,
                     const std::string& source, const std::string& what);

// The same for a map node inside a larger document (messages keep the document's lines).
void read_param_yaml(const std::vector<ParamField>& fields, const YAML::Node& map, const std::string& source,
                     const std::string& what);

// A YAML document of every field (full precision), nested maps for "outer.inner" keys.
std::string write_param_yaml(const std::vector<ParamField>& fields);

// The whole file as text; throws mppi::Error "<path>: cannot open <what> file".
std::string read_text_file(const std::string& path, const std::string& what);

}  // namespace mppi
