#include "base/param_yaml.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "base/error.hpp"
#include "base/yaml_number.hpp"

namespace mppi {

namespace {

// The keys directly under one map level: "tyre.B" belongs to the nested map "tyre".
std::string key_list(const std::vector<ParamField>& fields, const std::string& prefix) {
  std::string out;
  std::set<std::string> listed;
  for (const ParamField& f : fields) {
    const std::string key = f.key;
    if (key.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = key.substr(prefix.size());
    const std::string head = rest.substr(0, rest.find('.'));
    if (listed.insert(head).second) out += (out.empty() ? "" : ", ") + head;
  }
  return out;
}

// True if the field's range takes an infinity (so the YAML reader must accept .inf).
bool in_range_at_infinity(const ParamField& f) {
  ParamField probe = f;
  double v = kInf;
  probe.value = &v;
  probe.value_f = nullptr;
  if (in_range(probe)) return true;
  v = -kInf;
  return in_range(probe);
}

void read_map(const YAML::Node& map, const std::vector<ParamField>& fields, const std::string& prefix,
              const std::string& source, const std::string& what) {
  if (!map.IsMap())
    throw Error(yaml_where(source, map.Mark()) + ": " + what + " must be a mapping of key: number");
  std::set<std::string> seen;
  for (const auto& item : map) {
    const YAML::Node& key_node = item.first;
    const std::string key = key_node.IsScalar() ? key_node.Scalar() : std::string("<non-scalar key>");
    const std::string at = yaml_where(source, key_node.Mark());
    if (!seen.insert(key).second) throw Error(at + ": key '" + key + "' given twice in " + what);
    const std::string full = prefix + key;
    const ParamField* target = nullptr;
    bool nested = false;
    for (const ParamField& f : fields) {
      const std::string k = f.key;
      if (k == full) target = &f;
      if (k.compare(0, full.size() + 1, full + ".") == 0) nested = true;
    }
    if (nested) {
      read_map(item.second, fields, full + ".", source, what + " '" + key + "'");
      continue;
    }
    if (!target)
      throw Error(at + ": unknown key '" + key + "' in " + what + " (known: " + key_list(fields, prefix) + ")");
    target->set(yaml_number(item.second, key, source, /*allow_infinite=*/in_range_at_infinity(*target)));
    if (!in_range(*target))
      throw Error(yaml_where(source, item.second.Mark()) + ": key '" + key + "' must be " +
                  range_text(*target) + " (" + what + ")");
  }
}

}  // namespace

void read_param_yaml(const std::vector<ParamField>& fields, const std::string& text,
                     const std::string& source, const std::string& what) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(yaml_where(source, e.mark) + ": YAML syntax error: " + e.msg);
  }
  if (!root.IsDefined() || root.IsNull()) return;  // empty document: values unchanged
  read_map(root, fields, "", source, what);
}

void read_param_yaml(const std::vector<ParamField>& fields, const YAML::Node& map, const std::string& source,
                     const std::string& what) {
  if (!map.IsDefined() || map.IsNull()) return;
  read_map(map, fields, "", source, what);
}

// A number as YAML writes it (.inf, -.inf for the infinities some ranges allow).
std::string yaml_scalar(double v) {
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string write_param_yaml(const std::vector<ParamField>& fields) {
  std::ostringstream out;
  out.precision(17);
  // Top-level keys first, then each nested map in the order its first key appears.
  std::vector<std::string> groups;
  for (const ParamField& f : fields) {
    const std::string key = f.key;
    const auto dot = key.find('.');
    if (dot == std::string::npos) {
      out << key << ": " << yaml_scalar(f.get()) << "\n";
    } else {
      const std::string group = key.substr(0, dot);
      bool known = false;
      for (const auto& g : groups) known = known || g == group;
      if (!known) groups.push_back(group);
    }
  }
  for (const auto& group : groups) {
    out << group << ":\n";
    for (const ParamField& f : fields) {
      const std::string key = f.key;
      if (key.compare(0, group.size() + 1, group + ".") == 0)
        out << "  " << key.substr(group.size() + 1) << ": " << yaml_scalar(f.get()) << "\n";
    }
  }
  return out.str();
}

std::string read_text_file(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open " + what + " file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

}  // namespace mppi
