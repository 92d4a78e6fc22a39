#pragma once
// What the four-wheel models' descriptors share: the state names (the common states, the four
// wheel speeds, then a model's own) and the state from a simulated car's: the same model's
// state is copied whole; from another plant, the common states with the wheels rolling at
// v_x / R and the rest (suspension) at rest.
#include <algorithm>
#include <initializer_list>
#include <string>
#include <vector>

#include "dynamics/model_descriptor.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

template <class M>
void four_wheel_from_plant(const float* px, int plant_states, float radius_m, float* mx) {
  if (plant_states == M::kNx) {
    std::copy(px, px + M::kNx, mx);
    return;
  }
  std::fill(mx, mx + M::kNx, 0.f);
  std::copy(px, px + state::kCommonStates, mx);
  for (int i = 0; i < 4; ++i) mx[M::kOmega + i] = px[state::kVx] / radius_m;
}

// The common state names, the four wheel speeds', then `after_wheels`.
inline std::vector<std::string> four_wheel_state_names(std::initializer_list<std::string> after_wheels = {}) {
  std::vector<std::string> names =
      common_state_names_and({"omega_lf_radps", "omega_rf_radps", "omega_lr_radps", "omega_rr_radps"});
  names.insert(names.end(), after_wheels);
  return names;
}

// The descriptor part of a four-wheel model (M::params().base: its single-track parameters).
template <class M, class P, P (*load_params)(const std::string&),
          P (*read_params)(const std::string& text, const std::string& source)>
struct FourWheelDescriptor : ParamTableDescriptor<M, P, load_params, read_params> {
  static void from_plant(const M& m, const float* px, int plant_states, float* mx) {
    four_wheel_from_plant<M>(px, plant_states, static_cast<float>(m.params().base.wheel_radius_m), mx);
  }
};

}  // namespace mppi
