#pragma once
// The single-track (bicycle) model with Pacejka tyres (dynamics/single_track.hpp) as the
// registry knows it.
#include <algorithm>
#include <string>
#include <vector>

#include "dynamics/model_descriptor.hpp"
#include "dynamics/single_track.hpp"
#include "dynamics/vehicle_params.hpp"

namespace mppi::models {

struct SingleTrackModel : ParamTableDescriptor<SingleTrack, SingleTrackParams, load_single_track_params,
                                               single_track_params_from_yaml> {
  static constexpr const char* kName = "single-track";
  static constexpr const char* kSummary = "single-track physics: Pacejka tyres, wheel spin, load transfer, DC-motor drive";
  static constexpr const char* kDefaultFile = "config/autorally_single_track.yaml";
  static std::vector<std::string> state_names() {
    return common_state_names_and({"omega_front_radps", "omega_rear_radps"});
  }
  // The same model's state is copied whole; another plant's wheels roll at v_x / R.
  static void from_plant(const Model& m, const float* px, int plant_states, float* mx) {
    if (plant_states == Model::kNx) {
      std::copy(px, px + Model::kNx, mx);
      return;
    }
    const float radius = static_cast<float>(m.params().wheel_radius_m);
    std::copy(px, px + state::kCommonStates, mx);
    mx[Model::kOmegaFront] = mx[Model::kOmegaRear] = px[state::kVx] / radius;
  }

  // GPU twin: vulkan/shaders/models/single_track.glsl, in SingleTrackCoeffs<float> terms.
  static constexpr const char* kGpuKernel = "single_track";
  static std::vector<GpuField<Model>> gpu_fields() {
#define MPPI_COEFF(name, member) \
  {name, [](const Model& m) { return SingleTrackCoeffs<float>::from(m.params()).member; }}
    return {MPPI_COEFF("K_INV_MASS", inv_mass),
            MPPI_COEFF("K_INV_IZ", inv_yaw_inertia),
            MPPI_COEFF("K_LF", lf),
            MPPI_COEFF("K_LR", lr),
            MPPI_COEFF("K_H", h),
            MPPI_COEFF("K_RADIUS", radius),
            MPPI_COEFF("K_INV_IF", inv_front_inertia),
            MPPI_COEFF("K_INV_IR", inv_rear_inertia),
            MPPI_COEFF("K_WEIGHT", weight),
            MPPI_COEFF("K_MAX_STEER", max_steer),
            MPPI_COEFF("K_STALL", stall_torque),
            MPPI_COEFF("K_BRAKE_RATIO", brake_ratio),
            MPPI_COEFF("K_INV_NO_LOAD", inv_no_load_speed),
            MPPI_COEFF("K_ROLLING", rolling_force),
            MPPI_COEFF("K_INV_ROLLING_SPEED", inv_rolling_speed),
            MPPI_COEFF("K_DRAG", drag),
            MPPI_COEFF("K_SLIP_FLOOR", slip_floor),
            MPPI_COEFF("K_INV_SLIP_BLEND", inv_slip_blend),
            MPPI_COEFF("K_FRONT_DRIVE", front_drive),
            MPPI_COEFF("K_REAR_DRIVE", rear_drive),
            MPPI_COEFF("K_B", tyre.B),
            MPPI_COEFF("K_C", tyre.C),
            MPPI_COEFF("K_D", tyre.D),
            MPPI_COEFF("K_E", tyre.E),
            MPPI_COEFF("K_SH", tyre.Sh),
            MPPI_COEFF("K_SV", tyre.Sv),
            MPPI_COEFF("K_RB", rear_tyre.B),
            MPPI_COEFF("K_RC", rear_tyre.C),
            MPPI_COEFF("K_RD", rear_tyre.D)};
#undef MPPI_COEFF
  }
};
MPPI_REGISTER_MODEL(SingleTrackModel);

}  // namespace mppi::models
