#include "sim/actuator_model.hpp"

#include <algorithm>

#include "base/error.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/effects.hpp"

namespace mppi::sim {
namespace {

// The tighter of a rate limit [1/s] (0 = none) and a slew [s per unit] (0 = none), as a rate.
float tighter_rate(float rate_per_s, double slew_s) {
  if (slew_s <= 0.0) return rate_per_s;
  const auto from_slew = static_cast<float>(1.0 / slew_s);
  return rate_per_s > 0.f ? std::min(rate_per_s, from_slew) : from_slew;
}

}  // namespace

std::vector<ActuatorChannel> actuator_channels(const ActuatorLimits& limits, const EffectParams* effects) {
  ActuatorChannel steer{limits.steer_delay_s, 0.f, limits.steer_rate_per_s};
  ActuatorChannel throttle{limits.throttle_delay_s, 0.f, limits.throttle_rate_per_s};
  if (effects) {
    steer.delay_s += static_cast<float>(effects->steer_delay_s);
    throttle.delay_s += static_cast<float>(effects->throttle_delay_s);
    steer.lag_s = static_cast<float>(effects->steer_lag_s);
    throttle.lag_s = static_cast<float>(effects->throttle_lag_s);
    steer.rate_per_s = tighter_rate(steer.rate_per_s, effects->steer_slew_s);
    throttle.rate_per_s = tighter_rate(throttle.rate_per_s, effects->throttle_slew_s);
  }
  return {steer, throttle};
}

std::vector<ActuatorChannel> resolve_actuator_model(const std::string& source, const std::string& plant,
                                                    const std::string& plant_params_yaml,
                                                    const ActuatorLimits& limits) {
  if (source.empty() || source == "none") return {};
  if (source == "plant") {
    if (plant != "corrected") return actuator_channels(limits, nullptr);
    if (plant_params_yaml.empty()) throw Error("--actuator-model plant: the corrected plant needs --plant-params FILE");
    const EffectParams effects = load_corrected_model(plant_params_yaml).effects;
    return actuator_channels(limits, &effects);
  }
  const EffectParams effects = load_corrected_model(source).effects;
  return actuator_channels(ActuatorLimits{0.f, 0.f}, &effects);
}

}  // namespace mppi::sim
