#include "sim/corrected_limit_vehicle.hpp"

#include <type_traits>

namespace mppi::sim {

std::optional<SingleTrackParams> corrected_limit_lap_vehicle(const CorrectedModelFile& file) {
  bool single_track_params = false;  // the nominal's parameters are SingleTrackParams themselves
  visit_by_name(CorrectedNominalModels{}, file.nominal_model, [&]<class D>() {
    if constexpr (HasParamTable<D>) single_track_params = std::is_same_v<typename D::Params, SingleTrackParams>;
  });
  if (!single_track_params) return std::nullopt;
  EffectParams car_effects;  // only the effects named in the header; the rest stay at "off"
  car_effects.mass_scale = file.effects.mass_scale;
  car_effects.yaw_inertia_scale = file.effects.yaw_inertia_scale;
  car_effects.tyre_peak_scale = file.effects.tyre_peak_scale;
  car_effects.tyre_stiffness_scale = file.effects.tyre_stiffness_scale;
  const double grip_from_start = file.effects.grip_change_time_s <= 0.0 ? file.effects.grip_scale : 1.0;
  return apply_effect_params(file.nominal, car_effects, grip_from_start);
}

}  // namespace mppi::sim
