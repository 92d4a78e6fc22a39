#pragma once
// A corrected model as a file: a registered nominal model, its parameters and the effects
// around it (WithEffects<Model>, dynamics/with_effects.hpp), as `mppi-fit diagnose` writes it
// and `mppi-sim --model corrected` / `--plant corrected` read it.
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "dynamics/effects.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi {

// The corrected-model file (YAML; written by mppi-fit diagnose, docs/DIAGNOSE.md):
//   model: corrected
//   nominal: single-track
//   nominal_params: { <single-track keys, as in data/config/autorally_single_track.yaml> }
//   effects: { <EffectParams field>: value, ... }
// Unknown keys, non-numbers and invalid values throw mppi::Error naming the file and key.
//   nominal: double-track | full-vehicle | kinematic | autorally-nn (then nominal_params holds
//   that model's keys, for the network `network_npz: PATH` (empty = the shipped AutoRally
//   network), and the effects wrap it: WithEffects<...>, dynamics/with_effects.hpp)
struct CorrectedModelFile {
  std::string nominal_model = mppi::models::SingleTrackModel::kName;  // one of kCorrectedNominalModels
  SingleTrackParams nominal;          // single-track: the model; four-wheel: their core
  DoubleTrackParams double_track;     // nominal_model == double-track
  FullVehicleParams full_vehicle;     // nominal_model == full-vehicle
  KinematicBicycleParams kinematic;   // nominal_model == kinematic
  std::string network_npz;            // nominal_model == autorally-nn ("" = the shipped network)
  EffectParams effects;
  std::vector<std::string> selected;  // effect ids (informational, `selected:` list)
  // What the model was fitted on (`fitted_on:`, written by mppi-fit diagnose; informational
  // except for mppi-fit evaluate's match check): source, vehicle, throttle_command, dt_s.
  std::map<std::string, std::string> fitted_on;
};
// The registered models a corrected-model file can have as its nominal (the file has a
// parameter section for each of them).
using CorrectedNominalModels = TypeList<models::SingleTrackModel, models::DoubleTrackModel, models::FullVehicleModel,
                                        models::Kinematic, models::AutoRallyNetworkModel>;
inline const std::string kCorrectedNominalModels = names_of(CorrectedNominalModels{});
inline bool is_corrected_nominal_model(const std::string& name) {
  return visit_by_name(CorrectedNominalModels{}, name, []<class D>() {});
}

// The nominal model of a file as the registered model D (one of CorrectedNominalModels); a
// model whose data are weights is loaded from `weights_path` (the file's network_npz resolved
// by the caller).
template <class D>
typename D::Model corrected_nominal(const CorrectedModelFile& file, const std::string& weights_path) {
  using M = typename D::Model;
  if constexpr (std::is_constructible_v<M, const SingleTrackParams&>) return M(file.nominal);
  else if constexpr (std::is_constructible_v<M, const DoubleTrackParams&>) return M(file.double_track);
  else if constexpr (std::is_constructible_v<M, const FullVehicleParams&>) return M(file.full_vehicle);
  else if constexpr (std::is_constructible_v<M, const KinematicBicycleParams&>) return M(file.kinematic);
  else return D::load(weights_path);
}

CorrectedModelFile load_corrected_model(const std::string& path);
CorrectedModelFile corrected_model_from_yaml(const std::string& text, const std::string& source);
// YAML text of a corrected-model file.
std::string corrected_model_to_yaml(const CorrectedModelFile& model, const std::string& comment = "");

}  // namespace mppi
