// YAML <-> the physics models' parameters, through their parameter tables
// (dynamics/vehicle_params.hpp, base/param_yaml.hpp): strict, every mistake is an mppi::Error
// naming the file, line and key.
#include <string>
#include <vector>

#include "base/error.hpp"
#include "base/param_yaml.hpp"
#include "dynamics/models/double_track_model.hpp"
#include "dynamics/models/full_vehicle_model.hpp"
#include "dynamics/models/kinematic_model.hpp"
#include "dynamics/models/single_track_model.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi {

namespace {

// Reads the table of `p` from YAML text, then checks the conditions between fields.
template <class P>
P params_from_yaml(P p, const std::string& text, const std::string& source, const std::string& what) {
  read_param_yaml(param_table(p), text, source, what + " parameters");
  std::string why;
  if (!p.is_valid(&why)) throw Error(source + ": invalid " + what + " parameters: " + why);
  return p;
}

template <class P>
std::vector<NamedParam> named(P& p) {
  std::vector<NamedParam> out;
  for (const ParamField& f : param_table(p)) out.push_back({f.key, f.value});
  return out;
}

template <class P>
std::string yaml_of(const P& p) {
  P copy = p;
  return write_param_yaml(param_table(copy));
}

}  // namespace

SingleTrackParams single_track_params_from_yaml(const std::string& text, const std::string& source) {
  return params_from_yaml(SingleTrackParams{}, text, source, models::SingleTrackModel::kName);
}
DoubleTrackParams double_track_params_from_yaml(const std::string& text, const std::string& source) {
  return params_from_yaml(DoubleTrackParams{}, text, source, models::DoubleTrackModel::kName);
}
FullVehicleParams full_vehicle_params_from_yaml(const std::string& text, const std::string& source) {
  return params_from_yaml(FullVehicleParams{}, text, source, models::FullVehicleModel::kName);
}
KinematicBicycleParams kinematic_bicycle_params_from_yaml(const std::string& text,
                                                          const std::string& source) {
  return params_from_yaml(KinematicBicycleParams{}, text, source, models::Kinematic::kName);
}

SingleTrackParams load_single_track_params(const std::string& path) {
  return single_track_params_from_yaml(read_text_file(path, "single-track parameter"), path);
}
DoubleTrackParams load_double_track_params(const std::string& path) {
  return double_track_params_from_yaml(read_text_file(path, "double-track parameter"), path);
}
FullVehicleParams load_full_vehicle_params(const std::string& path) {
  return full_vehicle_params_from_yaml(read_text_file(path, "full-vehicle parameter"), path);
}
KinematicBicycleParams load_kinematic_bicycle_params(const std::string& path) {
  return kinematic_bicycle_params_from_yaml(read_text_file(path, "kinematic bicycle parameter"), path);
}

std::vector<NamedParam> named_parameters(SingleTrackParams& p) { return named(p); }
std::vector<NamedParam> named_parameters(DoubleTrackParams& p) { return named(p); }
std::vector<NamedParam> named_parameters(FullVehicleParams& p) { return named(p); }

std::string to_yaml(const SingleTrackParams& p) { return yaml_of(p); }
std::string to_yaml(const DoubleTrackParams& p) { return yaml_of(p); }
std::string to_yaml(const FullVehicleParams& p) { return yaml_of(p); }

}  // namespace mppi
