// YAML <-> corrected-model file (dynamics/corrected_model.hpp), strict like the other
// parameter readers: unknown keys, non-numbers and invalid values name the file and key. The
// effects are read and written through the effect table (dynamics/effects.hpp).
#include <cstdio>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "base/error.hpp"
#include "base/param_yaml.hpp"
#include "base/yaml_number.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/model_registry.hpp"

namespace mppi {
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
  if (out.nominal_model == mppi::models::DoubleTrackModel::kName) {
    if (!nominal_text.empty()) out.double_track = double_track_params_from_yaml(nominal_text, where);
    out.nominal = out.double_track.base;
  } else if (out.nominal_model == mppi::models::FullVehicleModel::kName) {
    if (!nominal_text.empty()) out.full_vehicle = full_vehicle_params_from_yaml(nominal_text, where);
    out.nominal = out.full_vehicle.base;
  } else if (out.nominal_model == mppi::models::Kinematic::kName) {
    if (!nominal_text.empty()) out.kinematic = kinematic_bicycle_params_from_yaml(nominal_text, where);
  } else if (out.nominal_model == mppi::models::AutoRallyNetworkModel::kName) {
    if (!nominal_text.empty()) {
      if (!nominal_node.IsMap()) throw Error(where + ": expected a map with network_npz");
      for (const auto& kv : nominal_node) {
        const std::string k = yaml_text(kv.first, "a key", where);
        if (k != "network_npz") throw Error(yaml_where(where, kv.first.Mark()) + ": unknown key '" + k + "' (valid: network_npz)");
        out.network_npz = kv.second.IsNull() ? "" : yaml_text(kv.second, "network_npz", where);
      }
    }
  } else if (!nominal_text.empty()) {
    out.nominal = single_track_params_from_yaml(nominal_text, where);
  }
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
  if (m.nominal_model == mppi::models::AutoRallyNetworkModel::kName) {
    o << "nominal_params:\n  network_npz: \"" << m.network_npz << "\"\n";
    return o.str();
  }
  std::string nominal_yaml;
  if (m.nominal_model == mppi::models::Kinematic::kName) {
    KinematicBicycleParams k = m.kinematic;
    nominal_yaml = write_param_yaml(param_table(k));
  } else if (m.nominal_model == mppi::models::DoubleTrackModel::kName) {
    nominal_yaml = to_yaml(m.double_track);
  } else if (m.nominal_model == mppi::models::FullVehicleModel::kName) {
    nominal_yaml = to_yaml(m.full_vehicle);
  } else {
    nominal_yaml = to_yaml(m.nominal);
  }
  std::istringstream lines(nominal_yaml);
  o << "nominal_params:\n";
  for (std::string line; std::getline(lines, line);)
    if (!line.empty() && line[0] != '#') o << "  " << line << "\n";
  return o.str();
}

}  // namespace mppi
