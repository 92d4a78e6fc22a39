#pragma once
// The double-track (four-wheel) model (dynamics/double_track.hpp) as the registry knows it.
#include <string>
#include <vector>

#include "dynamics/double_track.hpp"
#include "dynamics/four_wheel_observe.hpp"
#include "dynamics/model_descriptor.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi::models {

struct DoubleTrackModel : FourWheelDescriptor<DoubleTrack, DoubleTrackParams, load_double_track_params,
                                              double_track_params_from_yaml> {
  static constexpr const char* kName = "double-track";
  static constexpr const char* kSummary = "double-track (four-wheel) physics with lateral load transfer";
  static constexpr const char* kDefaultFile = "config/autorally_double_track.yaml";
  static std::vector<std::string> state_names() { return four_wheel_state_names(); }
};
MPPI_REGISTER_MODEL(DoubleTrackModel);

}  // namespace mppi::models
