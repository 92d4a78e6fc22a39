#pragma once
// Field tables of the models' parameters: YAML key -> member, only the keys an estimator may
// sensibly change; nullptr for any other key.
#include <string>

#include "dynamics/vehicle_params.hpp"
#include "sysid/calibration_actuators.hpp"

namespace mppi::sysid::detail {

double* single_track_field(SingleTrackParams& p, const std::string& n);
double* full_vehicle_field(FullVehicleParams& p, const std::string& n);
double* double_track_field(DoubleTrackParams& p, const std::string& n);
double* actuator_field(Actuators& a, const std::string& n);
double* single_track_or_actuator_field(SingleTrackWithActuators& p, const std::string& n);

bool is_actuator_param(const std::string& n);
// Estimated as the value itself; every other parameter is positive and estimated as its log.
bool is_linear_param(const std::string& n);

}  // namespace mppi::sysid::detail
