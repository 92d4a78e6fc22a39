#pragma once
// A corrected model as a file: a registered nominal model, its parameters and the effects
// around it (WithEffects<Model>, dynamics/with_effects.hpp), as `mppi-fit diagnose` writes it
// and `mppi-sim --model corrected` / `--plant corrected` read it.
#include <map>
#include <string>
#include <tuple>
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
// A model with a parameter table reads and writes its keys through its descriptor
// (params_from_yaml, params_to_yaml); the file keeps them in the member nominal_params_of<D>.
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

// The member of `file` that holds the parameters of the nominal model D (one of
// CorrectedNominalModels with a parameter table): the one of type D::Params. Picked by type, so
// a new nominal model with a parameter table needs a member of its own (else this fails to
// compile).
template <class D>
  requires HasParamTable<D>
typename D::Params& nominal_params_of(CorrectedModelFile& file) {
  return std::get<typename D::Params&>(std::tie(file.nominal, file.double_track, file.full_vehicle, file.kinematic));
}
template <class D>
  requires HasParamTable<D>
const typename D::Params& nominal_params_of(const CorrectedModelFile& file) {
  return std::get<const typename D::Params&>(
      std::tie(file.nominal, file.double_track, file.full_vehicle, file.kinematic));
}

// The nominal model of a file as the registered model D (one of CorrectedNominalModels); a
// model whose data are weights is loaded from `weights_path` (the file's network_npz resolved
// by the caller).
template <class D>
typename D::Model corrected_nominal(const CorrectedModelFile& file, const std::string& weights_path) {
  if constexpr (HasParamTable<D>) return D::make(nominal_params_of<D>(file));
  else return D::load(weights_path);
}

CorrectedModelFile load_corrected_model(const std::string& path);
CorrectedModelFile corrected_model_from_yaml(const std::string& text, const std::string& source);
// YAML text of a corrected-model file.
std::string corrected_model_to_yaml(const CorrectedModelFile& model, const std::string& comment = "");

}  // namespace mppi
