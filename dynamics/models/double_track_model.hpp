#pragma once
// The double-track (four-wheel) model (dynamics/double_track.hpp) as the registry knows it.
#include <string>
#include <vector>

#include "dynamics/double_track.hpp"
#include "dynamics/four_wheel_observe.hpp"
#include "dynamics/model_descriptor.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi::models {

struct DoubleTrackModel {
  using Model = DoubleTrack;
  using Params = DoubleTrackParams;
  static constexpr const char* kName = "double-track";
  static constexpr const char* kSummary = "double-track (four-wheel) physics with lateral load transfer";
  static constexpr const char* kDefaultFile = "config/autorally_double_track.yaml";
  static std::vector<ParamField> params(Params& p) { return param_table(p); }
  static Model make(const Params& p) { return Model(p); }
  static Model load(const std::string& path) {
    return Model(path.empty() ? Params{} : load_double_track_params(path));
  }
  static std::vector<std::string> state_names() {
    auto names = common_state_names();
    names.insert(names.end(), {"omega_lf_radps", "omega_rf_radps", "omega_lr_radps", "omega_rr_radps"});
    return names;
  }
  static void from_plant(const Model& m, const float* px, int plant_states, float* mx) {
    four_wheel_from_plant<Model>(px, plant_states, static_cast<float>(m.params().base.wheel_radius_m), mx);
  }
};
MPPI_REGISTER_MODEL(DoubleTrackModel);

}  // namespace mppi::models
