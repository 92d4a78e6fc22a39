// YAML <-> corrected-model file (dynamics/corrected_single_track.hpp), strict like the other
// parameter readers: unknown keys, non-numbers and invalid values name the file and key.
#include <cstdio>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "dynamics/corrected_single_track.hpp"
#include "dynamics/model_registry.hpp"
#include "mppi/error.hpp"
#include "mppi/yaml_number.hpp"

namespace mppi {
namespace {

struct EffectField {
  const char* key;
  double EffectParams::*member;
};

constexpr EffectField kEffectFields[] = {
    {"steer_offset", &EffectParams::steer_offset},
    {"steer_gain", &EffectParams::steer_gain},
    {"throttle_offset", &EffectParams::throttle_offset},
    {"steer_delay_s", &EffectParams::steer_delay_s},
    {"throttle_delay_s", &EffectParams::throttle_delay_s},
    {"steer_lag_s", &EffectParams::steer_lag_s},
    {"throttle_lag_s", &EffectParams::throttle_lag_s},
    {"aero_drag_kgpm", &EffectParams::aero_drag_kgpm},
    {"rolling_force_N", &EffectParams::rolling_force_N},
    {"rolling_viscous_Nspm", &EffectParams::rolling_viscous_Nspm},
    {"tyre_peak_scale", &EffectParams::tyre_peak_scale},
    {"tyre_stiffness_scale", &EffectParams::tyre_stiffness_scale},
    {"grip_scale", &EffectParams::grip_scale},
    {"grip_change_time_s", &EffectParams::grip_change_time_s},
    {"cg_height_delta_m", &EffectParams::cg_height_delta_m},
    {"voltage_sag", &EffectParams::voltage_sag},
    {"grade_x", &EffectParams::grade_x},
    {"grade_y", &EffectParams::grade_y},
};

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
    const std::string key = kv.first.as<std::string>();
    const YAML::Node& v = kv.second;
    if (key == "model") {
      if (v.as<std::string>() != "corrected")
        throw Error(yaml_where(source, v.Mark()) + ": model must be 'corrected'");
    } else if (key == "nominal") {
      out.nominal_model = v.as<std::string>();
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
      if (!v.IsMap()) throw Error(yaml_where(source, v.Mark()) + ": effects must be a map");
      for (const auto& e : v) {
        const std::string name = e.first.as<std::string>();
        bool found = false;
        for (const auto& f : kEffectFields)
          if (name == f.key) {
            out.effects.*(f.member) = yaml_number(e.second, name, source);
            found = true;
          }
        if (!found) {
          std::string valid;
          for (const auto& f : kEffectFields) valid += (valid.empty() ? "" : ", ") + std::string(f.key);
          throw Error(yaml_where(source, e.first.Mark()) + ": unknown effect parameter '" + name +
                      "' (valid: " + valid + ")");
        }
      }
    } else if (key == "selected") {
      if (!v.IsSequence()) throw Error(yaml_where(source, v.Mark()) + ": selected must be a list");
      for (const auto& s : v) out.selected.push_back(s.as<std::string>());
    } else {
      throw Error(yaml_where(source, kv.first.Mark()) + ": unknown key '" + key +
                  "' (valid: model, nominal, nominal_params, effects, selected)");
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
        const std::string k = kv.first.as<std::string>();
        if (k != "network_npz") throw Error(yaml_where(where, kv.first.Mark()) + ": unknown key '" + k + "' (valid: network_npz)");
        out.network_npz = kv.second.IsNull() ? "" : kv.second.as<std::string>();
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
  const EffectParams defaults;
  std::ostringstream eff;
  eff.precision(10);
  for (const auto& f : kEffectFields)
    if (m.effects.*(f.member) != defaults.*(f.member)) eff << "  " << f.key << ": " << m.effects.*(f.member) << "\n";
  o << (eff.str().empty() ? "effects: {}\n" : "effects:\n" + eff.str());
  if (m.nominal_model == mppi::models::Kinematic::kName) {
    const KinematicBicycleParams& k = m.kinematic;
    o << "nominal_params:\n  wheelbase_m: " << k.wheelbase_m << "\n  max_steer_rad: " << k.max_steer_rad
      << "\n  max_accel_mps2: " << k.max_accel_mps2 << "\n  speed_damping_per_s: " << k.speed_damping_per_s << "\n";
    return o.str();
  }
  if (m.nominal_model == mppi::models::AutoRallyNetworkModel::kName) {
    o << "nominal_params:\n  network_npz: \"" << m.network_npz << "\"\n";
    return o.str();
  }
  if (m.nominal_model == mppi::models::DoubleTrackModel::kName || m.nominal_model == mppi::models::FullVehicleModel::kName) {
    std::istringstream lines(m.nominal_model == mppi::models::DoubleTrackModel::kName ? to_yaml(m.double_track) : to_yaml(m.full_vehicle));
    o << "nominal_params:\n";
    for (std::string line; std::getline(lines, line);)
      if (!line.empty() && line[0] != '#') o << "  " << line << "\n";
    return o.str();
  }
  const SingleTrackParams& p = m.nominal;
  o << "nominal_params:\n"
    << "  mass_kg: " << p.mass_kg << "\n  yaw_inertia_kgm2: " << p.yaw_inertia_kgm2
    << "\n  cg_to_front_axle_m: " << p.cg_to_front_axle_m << "\n  cg_to_rear_axle_m: " << p.cg_to_rear_axle_m
    << "\n  cg_height_m: " << p.cg_height_m << "\n  wheel_radius_m: " << p.wheel_radius_m
    << "\n  front_wheel_inertia_kgm2: " << p.front_wheel_inertia_kgm2
    << "\n  rear_wheel_inertia_kgm2: " << p.rear_wheel_inertia_kgm2 << "\n  gravity_mps2: " << p.gravity_mps2
    << "\n  max_steer_rad: " << p.max_steer_rad << "\n  stall_torque_Nm: " << p.stall_torque_Nm
    << "\n  no_load_speed_mps: " << p.no_load_speed_mps << "\n  rolling_resistance: " << p.rolling_resistance
    << "\n  rolling_resistance_speed_mps: " << p.rolling_resistance_speed_mps
    << "\n  aero_drag_kgpm: " << p.aero_drag_kgpm << "\n  slip_speed_floor_mps: " << p.slip_speed_floor_mps
    << "\n  slip_blend: " << p.slip_blend << "\n  tyre:\n    B: " << p.tyre.B << "\n    C: " << p.tyre.C
    << "\n    D: " << p.tyre.D << "\n    E: " << p.tyre.E << "\n    Sh: " << p.tyre.Sh << "\n    Sv: " << p.tyre.Sv
    << "\n";
  return o.str();
}

}  // namespace mppi
