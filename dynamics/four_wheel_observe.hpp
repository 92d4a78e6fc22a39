#pragma once
// A four-wheel model's state from a simulated car's: the same model's state is copied whole;
// from another plant, the common states with the wheels rolling at v_x / R and the rest
// (suspension) at rest.
#include <algorithm>

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

}  // namespace mppi
