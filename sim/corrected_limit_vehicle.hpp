#pragma once
// The car whose limit lap (sim/limit_lap.hpp) a corrected-model plant's laps are measured
// against (plant_vehicle_params, RunSummary::limit_lap_s).
#include <optional>

#include "dynamics/corrected_model.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi::sim {

// For a file whose nominal is the single-track model: its nominal_params with the effects that
// are a different car in SingleTrackParams' own terms applied, as the plant applies them
// (apply_effect_params):
//   payload          mass x mass_scale, yaw inertia x yaw_inertia_scale
//   tire_saturation  tyre peak D x tyre_peak_scale, B x tyre_stiffness_scale / tyre_peak_scale
//   friction_change  D and Sv x grip_scale, only for a change from the start (grip_change_time_s
//                    <= 0: the whole run is on that grip)
// Every other effect leaves the reference the nominal car: command delays, lags and maps, road
// grade and bumps, grip patches, a grip change later in the run, motor, CG and drive changes
// (the limit lap is the reference of the car on flat, uniform ground, driven without actuator
// dynamics). None for a file with another nominal model.
std::optional<SingleTrackParams> corrected_limit_lap_vehicle(const CorrectedModelFile& file);

}  // namespace mppi::sim
