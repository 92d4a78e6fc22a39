#include "sim/corrected_limit_vehicle.hpp"

namespace mppi::sim {

std::optional<SingleTrackParams> corrected_limit_lap_vehicle(const CorrectedModelFile& file) {
  if (file.nominal_model != models::SingleTrackModel::kName) return std::nullopt;
  EffectParams car_effects;  // only the effects named in the header; the rest stay at "off"
  car_effects.mass_scale = file.effects.mass_scale;
  car_effects.yaw_inertia_scale = file.effects.yaw_inertia_scale;
  car_effects.tyre_peak_scale = file.effects.tyre_peak_scale;
  car_effects.tyre_stiffness_scale = file.effects.tyre_stiffness_scale;
  const double grip_from_start = file.effects.grip_change_time_s <= 0.0 ? file.effects.grip_scale : 1.0;
  return apply_effect_params(file.nominal, car_effects, grip_from_start);
}

}  // namespace mppi::sim
