#pragma once
// The kinematic bicycle (dynamics/kinematic_bicycle.hpp) as the registry knows it.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "dynamics/kinematic_bicycle.hpp"
#include "dynamics/model_descriptor.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi::models {

struct Kinematic : ParamTableDescriptor<KinematicBicycle, KinematicBicycleParams, load_kinematic_bicycle_params,
                                        kinematic_bicycle_params_from_yaml> {
  static constexpr const char* kName = "kinematic";
  static constexpr const char* kSummary = "kinematic bicycle (no tyre slip), reference point at the rear axle";
  static constexpr const char* kDefaultFile = "";
  static std::vector<std::string> state_names() { return common_state_names(); }
  // The kinematic bicycle's reference point is the rear axle, l_r behind a physics plant's CG.
  static void from_plant(const Model&, const float* px, int, float* mx) {
    const float l_r = static_cast<float>(SingleTrackParams{}.cg_to_rear_axle_m);
    std::copy(px, px + state::kCommonStates, mx);
    mx[state::kX] -= l_r * std::cos(px[state::kYaw]);
    mx[state::kY] -= l_r * std::sin(px[state::kYaw]);
    mx[state::kVy] = 0.f;
  }

  // GPU twin: vulkan/shaders/models/kinematic.glsl (as KinematicBicycle's constructor computes them).
  static constexpr const char* kGpuKernel = "kinematic";
  static std::vector<GpuField<Model>> gpu_fields() {
    return {{"K_INV_WHEELBASE", [](const Model& m) { return static_cast<float>(1 / m.params().wheelbase_m); }},
            {"K_MAX_STEER", [](const Model& m) { return static_cast<float>(m.params().max_steer_rad); }},
            {"K_MAX_ACCEL", [](const Model& m) { return static_cast<float>(m.params().max_accel_mps2); }},
            {"K_DAMPING", [](const Model& m) { return static_cast<float>(m.params().speed_damping_per_s); }}};
  }
};
MPPI_REGISTER_MODEL(Kinematic);

}  // namespace mppi::models
