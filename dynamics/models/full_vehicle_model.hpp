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

struct FullVehicleModel : FourWheelDescriptor<FullVehicle, FullVehicleParams, load_full_vehicle_params,
                                              full_vehicle_params_from_yaml> {
  static constexpr const char* kName = "full-vehicle";
  static constexpr const char* kSummary = "full vehicle: four wheels, sprung mass in heave, roll and pitch, aero drag";
  static constexpr const char* kDefaultFile = "config/autorally_full_vehicle.yaml";
  static std::vector<std::string> state_names() {
    return four_wheel_state_names({"pitch_rad", "heave_m", "roll_rate_radps", "pitch_rate_radps", "heave_rate_mps"});
  }
};
MPPI_REGISTER_MODEL(FullVehicleModel);

}  // namespace mppi::models
