#pragma once
// The full vehicle (dynamics/full_vehicle.hpp: planar four-wheel motion with a sprung mass in
// heave, roll and pitch) as the registry knows it.
#include <string>
#include <vector>

#include "dynamics/four_wheel_observe.hpp"
#include "dynamics/full_vehicle.hpp"
#include "dynamics/model_descriptor.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi::models {

struct FullVehicleModel {
  using Model = FullVehicle;
  using Params = FullVehicleParams;
  static constexpr const char* kName = "full-vehicle";
  static constexpr const char* kSummary = "full vehicle: four wheels, sprung mass in heave, roll and pitch, aero drag";
  static constexpr const char* kDefaultFile = "config/autorally_full_vehicle.yaml";
  static std::vector<ParamField> params(Params& p) { return param_table(p); }
  static Model make(const Params& p) { return Model(p); }
  static Model load(const std::string& path) {
    return Model(path.empty() ? Params{} : load_full_vehicle_params(path));
  }
  static std::vector<std::string> state_names() {
    auto names = common_state_names();
    names.insert(names.end(), {"omega_lf_radps", "omega_rf_radps", "omega_lr_radps", "omega_rr_radps",
                               "pitch_rad", "heave_m", "roll_rate_radps", "pitch_rate_radps",
                               "heave_rate_mps"});
    return names;
  }
  static void from_plant(const Model& m, const float* px, int plant_states, float* mx) {
    four_wheel_from_plant<Model>(px, plant_states, static_cast<float>(m.params().base.wheel_radius_m), mx);
  }
};
MPPI_REGISTER_MODEL(FullVehicleModel);

}  // namespace mppi::models
