// YAML <-> corrected-model file (dynamics/corrected_model.hpp), strict like the other
// parameter readers: unknown keys, non-numbers and invalid values name the file and key. The
// effects are read and written through the effect table (dynamics/effects.hpp), nominal_params
// through the nominal model's descriptor, found by name among CorrectedNominalModels.
#include <cstdio>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "base/error.hpp"
#include "base/param_yaml.hpp"
#include "base/yaml_number.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/with_effects.hpp"  // single_track_core

namespace mppi {
namespace {

// nominal_params of a model whose data are weights: `network_npz: PATH` (null = the shipped one).
void read_weights_section(const YAML::Node& node, const std::string& where, std::string& network_npz) {
  if (!node.IsMap()) throw Error(where + ": expected a map with network_npz");
  for (const auto& kv : node) {
    const std::string k = yaml_text(kv.first, "a key", where);
    if (k != "network_npz")
      throw Error(yaml_where(where, kv.first.Mark()) + ": unknown key '" + k + "' (valid: network_npz)");
    network_npz = kv.second.IsNull() ? "" : yaml_text(kv.second, "network_npz", where);
  }
}

// nominal_params into `out` for the nominal model D; an empty section keeps the defaults. A
// parameter table is read from the section's re-emitted `text` (error positions count from the
// section's first line); a weights section from its `node`.
template <class D>
void read_nominal_params(CorrectedModelFile& out, const std::string& text, const YAML::Node& node,
                         const std::string& where) {
  if constexpr (HasParamTable<D>) {
    typename D::Params& p = nominal_params_of<D>(out);
    if (!text.empty()) p = D::params_from_yaml(text, where);
    // `nominal` also carries a four-wheel set's single-track core (its mass and geometry).
    if constexpr (requires { single_track_core(p); }) out.nominal = single_track_core(p);
  } else if (!text.empty()) {
    read_weights_section(node, where, out.network_npz);
  }
}

// The nominal_params section for the nominal model D: every key of its parameter table (nested
// two spaces), or the weights file.
template <class D>
std::string nominal_params_yaml(const CorrectedModelFile& m) {
  if constexpr (HasParamTable<D>) {
    std::istringstream lines(D::params_to_yaml(nominal_params_of<D>(m)));
    std::string out = "nominal_params:\n";
    for (std::string line; std::getline(lines, line);)
      if (!line.empty() && line[0] != '#') out += "  " + line + "\n";
    return out;
  } else {
    return "nominal_params:\n  network_npz: \"" + m.network_npz + "\"\n";
  }
}

}  // namespace

CorrectedModelFile corrected_model_from_yaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(source + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) throw Error(source + ": expected a map with nominal_params and effects");
  CorrectedModelFile out;
  std::string nominal_text;  // parsed once the nominal model is known (keys in any order)
  YAML::Node nominal_node;
  for (const auto& kv : root) {
    const std::string key = yaml_text(kv.first, "a key", source);
    const YAML::Node& v = kv.second;
    if (key == "model") {
      if (yaml_text(v, "model", source) != "corrected")
        throw Error(yaml_where(source, v.Mark()) + ": model must be 'corrected'");
    } else if (key == "nominal") {
      out.nominal_model = yaml_text(v, "nominal", source);
      if (!is_corrected_nominal_model(out.nominal_model))
        throw Error(yaml_where(source, v.Mark()) + ": nominal must be one of " + kCorrectedNominalModels + ", got '" +
                    out.nominal_model + "'");
    } else if (key == "nominal_params") {
      YAML::Emitter em;
      em << v;
      nominal_text = em.c_str();
      if (nominal_text == "~" || nominal_text == "{}") nominal_text.clear();
      nominal_node = v;
    } else if (key == "effects") {
      read_param_yaml(param_table(out.effects), v, source, "effects");
    } else if (key == "selected") {
      if (!v.IsSequence()) throw Error(yaml_where(source, v.Mark()) + ": selected must be a list");
      for (const auto& s : v) out.selected.push_back(yaml_text(s, "an entry of selected", source));
    } else if (key == "fitted_on") {
      if (!v.IsMap()) throw Error(yaml_where(source, v.Mark()) + ": fitted_on must be a map of key: text");
      for (const auto& f : v)
        out.fitted_on[yaml_text(f.first, "a key of fitted_on", source)] = yaml_text(f.second, "a value of fitted_on", source);
    } else {
      throw Error(yaml_where(source, kv.first.Mark()) + ": unknown key '" + key +
                  "' (valid: model, nominal, nominal_params, effects, selected, fitted_on)");
    }
  }
  const std::string where = source + " (nominal_params)";
  with_model_in(
      CorrectedNominalModels{}, out.nominal_model,
      [&]<class D>() { read_nominal_params<D>(out, nominal_text, nominal_node, where); }, "nominal model");
  std::string why;
  if (!out.effects.is_valid(&why)) throw Error(source + ": effects: " + why);
  return out;
}

CorrectedModelFile load_corrected_model(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot open corrected-model file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return corrected_model_from_yaml(ss.str(), path);
}

std::string corrected_model_to_yaml(const CorrectedModelFile& m, const std::string& comment) {
  std::ostringstream o;
  o.precision(10);
  if (!comment.empty()) {
    std::istringstream lines(comment);
    std::string line;
    while (std::getline(lines, line)) o << "# " << line << "\n";
  }
  o << "model: corrected\nnominal: " << m.nominal_model << "\nselected: [";
  for (std::size_t i = 0; i < m.selected.size(); ++i) o << (i ? ", " : "") << m.selected[i];
  o << "]\n";
  // Only the effects that are on (values other than their defaults).
  EffectParams effects = m.effects, defaults;
  const std::vector<ParamField> fields = param_table(effects), default_fields = param_table(defaults);
  std::ostringstream eff;
  eff.precision(17);
  for (std::size_t i = 0; i < fields.size(); ++i)
    if (fields[i].get() != default_fields[i].get()) eff << "  " << fields[i].key << ": " << fields[i].get() << "\n";
  o << (eff.str().empty() ? "effects: {}\n" : "effects:\n" + eff.str());
  if (!m.fitted_on.empty()) {
    YAML::Emitter fitted;  // quoted as YAML needs (file names may hold ':' or '#')
    fitted << YAML::BeginMap;
    for (const auto& [k, v] : m.fitted_on) fitted << YAML::Key << k << YAML::Value << YAML::DoubleQuoted << v;
    fitted << YAML::EndMap;
    std::istringstream fitted_lines(fitted.c_str());
    o << "fitted_on:\n";
    for (std::string line; std::getline(fitted_lines, line);) o << "  " << line << "\n";
  }
  // A nominal model the file cannot name throws here: what was written could not be read back.
  o << with_model_in(
      CorrectedNominalModels{}, m.nominal_model, [&]<class D>() { return nominal_params_yaml<D>(m); }, "nominal model");
  return o.str();
}

}  // namespace mppi
