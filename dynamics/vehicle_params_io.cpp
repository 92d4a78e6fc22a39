// YAML -> SingleTrackParams / KinematicBicycleParams, strict: every mistake is an mppi::Error
// naming the file, line and key.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "dynamics/vehicle_params.hpp"
#include "mppi/error.hpp"
#include "mppi/yaml_number.hpp"

namespace mppi {

namespace {

struct Field {
  const char* key;
  double* value;
};

// "file:line:column" (1-based) of a node, or just "file" when yaml-cpp has no position.
std::string where(const std::string& source, const YAML::Mark& mark) { return yaml_where(source, mark); }

std::string key_list(const std::vector<Field>& fields, const char* extra = nullptr) {
  std::string out;
  for (const auto& f : fields) out += (out.empty() ? "" : ", ") + std::string(f.key);
  if (extra) out += std::string(", ") + extra;
  return out;
}

double read_number(const YAML::Node& value, const std::string& key, const std::string& source) {
  return yaml_number(value, key, source);
}

// Reads a map of key: number into `fields`. `nested_key`/`nested` (optional) handle one
// sub-map, e.g. tyre:. `what` names the parameter set in messages.
void read_map(const YAML::Node& map, const std::vector<Field>& fields, const std::string& source,
              const std::string& what, const char* nested_key = nullptr,
              const std::vector<Field>* nested = nullptr) {
  if (!map.IsMap()) throw Error(where(source, map.Mark()) + ": " + what + " must be a mapping of key: number");
  std::set<std::string> seen;
  for (const auto& item : map) {
    const YAML::Node& key_node = item.first;
    const std::string key = key_node.IsScalar() ? key_node.Scalar() : std::string("<non-scalar key>");
    const std::string at = where(source, key_node.Mark());
    if (!seen.insert(key).second) throw Error(at + ": key '" + key + "' given twice in " + what);
    if (nested_key && key == nested_key) {
      read_map(item.second, *nested, source, what + " '" + key + "'");
      continue;
    }
    double* target = nullptr;
    for (const auto& f : fields)
      if (key == f.key) target = f.value;
    if (!target)
      throw Error(at + ": unknown key '" + key + "' in " + what + " (known: " + key_list(fields, nested_key) + ")");
    *target = read_number(item.second, key, source);
  }
}

YAML::Node parse(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(where(source, e.mark) + ": YAML syntax error: " + e.msg);
  }
}

std::string read_file(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open " + what + " file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

}  // namespace

namespace {

// The single-track keys, shared by the double-track and full-vehicle files.
std::vector<Field> single_track_fields(SingleTrackParams& p, bool with_aero_drag = true) {
  std::vector<Field> fields = {
      {"mass_kg", &p.mass_kg},
      {"yaw_inertia_kgm2", &p.yaw_inertia_kgm2},
      {"cg_to_front_axle_m", &p.cg_to_front_axle_m},
      {"cg_to_rear_axle_m", &p.cg_to_rear_axle_m},
      {"cg_height_m", &p.cg_height_m},
      {"wheel_radius_m", &p.wheel_radius_m},
      {"front_wheel_inertia_kgm2", &p.front_wheel_inertia_kgm2},
      {"rear_wheel_inertia_kgm2", &p.rear_wheel_inertia_kgm2},
      {"gravity_mps2", &p.gravity_mps2},
      {"max_steer_rad", &p.max_steer_rad},
      {"stall_torque_Nm", &p.stall_torque_Nm},
      {"no_load_speed_mps", &p.no_load_speed_mps},
      {"rolling_resistance", &p.rolling_resistance},
      {"rolling_resistance_speed_mps", &p.rolling_resistance_speed_mps},
      {"aero_drag_kgpm", &p.aero_drag_kgpm},
      {"slip_speed_floor_mps", &p.slip_speed_floor_mps},
      {"slip_blend", &p.slip_blend},
  };
  if (!with_aero_drag)
    fields.erase(std::remove_if(fields.begin(), fields.end(),
                                [](const Field& f) { return std::string(f.key) == "aero_drag_kgpm"; }),
                 fields.end());
  return fields;
}

std::vector<Field> tyre_fields(PacejkaParams& t) {
  return {{"B", &t.B}, {"C", &t.C}, {"D", &t.D}, {"E", &t.E}, {"Sh", &t.Sh}, {"Sv", &t.Sv}};
}

std::vector<Field> double_track_fields(DoubleTrackParams& p) {
  std::vector<Field> f = single_track_fields(p.base);
  f.insert(f.end(), {{"front_track_m", &p.front_track_m},
                     {"rear_track_m", &p.rear_track_m},
                     {"front_roll_share", &p.front_roll_share},
                     {"lateral_load_transfer", &p.lateral_load_transfer}});
  return f;
}

std::vector<Field> full_vehicle_fields(FullVehicleParams& p) {
  std::vector<Field> f = single_track_fields(p.base, false);
  f.insert(f.end(), {{"front_track_m", &p.front_track_m},
                     {"rear_track_m", &p.rear_track_m},
                     {"front_wheel_mass_kg", &p.front_wheel_mass_kg},
                     {"rear_wheel_mass_kg", &p.rear_wheel_mass_kg},
                     {"front_spring_Npm", &p.front_spring_Npm},
                     {"rear_spring_Npm", &p.rear_spring_Npm},
                     {"front_damper_Nspm", &p.front_damper_Nspm},
                     {"rear_damper_Nspm", &p.rear_damper_Nspm},
                     {"sprung_cg_height_m", &p.sprung_cg_height_m},
                     {"roll_centre_height_m", &p.roll_centre_height_m},
                     {"roll_inertia_kgm2", &p.roll_inertia_kgm2},
                     {"pitch_inertia_kgm2", &p.pitch_inertia_kgm2},
                     {"drag_coefficient", &p.drag_coefficient},
                     {"air_density_kgpm3", &p.air_density_kgpm3},
                     {"frontal_area_m2", &p.frontal_area_m2}});
  return f;
}

// Reads `fields` (+ tyre:) from a document into the struct they point into, then validates.
template <class P>
P params_from_yaml(P p, std::vector<Field> (*fields_of)(P&), const std::string& text,
                   const std::string& source, const std::string& what) {
  const YAML::Node root = parse(text, source);
  if (root.IsDefined() && !root.IsNull()) {
    const std::vector<Field> fields = fields_of(p);
    const std::vector<Field> tyre = tyre_fields(p.base.tyre);
    read_map(root, fields, source, what + " parameters", "tyre", &tyre);
  }
  std::string why;
  if (!p.is_valid(&why)) throw Error(source + ": invalid " + what + " parameters: " + why);
  return p;
}

std::string fields_to_yaml(const std::vector<Field>& fields, const std::vector<Field>& tyre) {
  std::ostringstream out;
  out.precision(17);
  for (const auto& f : fields) out << f.key << ": " << *f.value << "\n";
  out << "tyre:\n";
  for (const auto& f : tyre) out << "  " << f.key << ": " << *f.value << "\n";
  return out.str();
}

}  // namespace

SingleTrackParams single_track_params_from_yaml(const std::string& text, const std::string& source) {
  SingleTrackParams p;
  const YAML::Node root = parse(text, source);
  if (!root.IsDefined() || root.IsNull()) return p;  // empty document: all defaults
  const std::vector<Field> fields = single_track_fields(p);
  const std::vector<Field> tyre = tyre_fields(p.tyre);
  read_map(root, fields, source, "single-track parameters", "tyre", &tyre);
  std::string why;
  if (!p.is_valid(&why)) throw Error(source + ": invalid single-track parameters: " + why);
  return p;
}

DoubleTrackParams double_track_params_from_yaml(const std::string& text, const std::string& source) {
  return params_from_yaml(DoubleTrackParams{}, &double_track_fields, text, source, "double-track");
}

FullVehicleParams full_vehicle_params_from_yaml(const std::string& text, const std::string& source) {
  return params_from_yaml(FullVehicleParams{}, &full_vehicle_fields, text, source, "full-vehicle");
}

DoubleTrackParams load_double_track_params(const std::string& path) {
  return double_track_params_from_yaml(read_file(path, "double-track parameter"), path);
}

FullVehicleParams load_full_vehicle_params(const std::string& path) {
  return full_vehicle_params_from_yaml(read_file(path, "full-vehicle parameter"), path);
}

namespace {
std::vector<NamedParam> named(const std::vector<Field>& fields, PacejkaParams& tyre) {
  std::vector<NamedParam> out;
  for (const auto& f : fields) out.push_back({f.key, f.value});
  for (const auto& f : tyre_fields(tyre)) out.push_back({std::string("tyre.") + f.key, f.value});
  return out;
}
}  // namespace

std::vector<NamedParam> named_parameters(SingleTrackParams& p) { return named(single_track_fields(p), p.tyre); }
std::vector<NamedParam> named_parameters(DoubleTrackParams& p) { return named(double_track_fields(p), p.base.tyre); }
std::vector<NamedParam> named_parameters(FullVehicleParams& p) { return named(full_vehicle_fields(p), p.base.tyre); }

std::string to_yaml(const SingleTrackParams& p) {
  SingleTrackParams c = p;
  return fields_to_yaml(single_track_fields(c), tyre_fields(c.tyre));
}

std::string to_yaml(const DoubleTrackParams& p) {
  DoubleTrackParams c = p;
  return fields_to_yaml(double_track_fields(c), tyre_fields(c.base.tyre));
}

std::string to_yaml(const FullVehicleParams& p) {
  FullVehicleParams c = p;
  return fields_to_yaml(full_vehicle_fields(c), tyre_fields(c.base.tyre));
}

KinematicBicycleParams kinematic_bicycle_params_from_yaml(const std::string& text,
                                                          const std::string& source) {
  KinematicBicycleParams p;
  const YAML::Node root = parse(text, source);
  if (!root.IsDefined() || root.IsNull()) return p;
  const std::vector<Field> fields = {
      {"wheelbase_m", &p.wheelbase_m},
      {"max_steer_rad", &p.max_steer_rad},
      {"max_accel_mps2", &p.max_accel_mps2},
      {"speed_damping_per_s", &p.speed_damping_per_s},
  };
  read_map(root, fields, source, "kinematic bicycle parameters");
  std::string why;
  if (!p.is_valid(&why)) throw Error(source + ": invalid kinematic bicycle parameters: " + why);
  return p;
}

SingleTrackParams load_single_track_params(const std::string& path) {
  return single_track_params_from_yaml(read_file(path, "single-track parameter"), path);
}

KinematicBicycleParams load_kinematic_bicycle_params(const std::string& path) {
  return kinematic_bicycle_params_from_yaml(read_file(path, "kinematic bicycle parameter"), path);
}

}  // namespace mppi
