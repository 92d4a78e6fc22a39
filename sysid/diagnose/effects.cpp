#include "sysid/diagnose/effects.hpp"

#include "mppi/error.hpp"

namespace mppi::diagnose {

const std::vector<EffectSpec>& effect_library() {
  using E = EffectParams;
  static const std::vector<EffectSpec> lib = {
      {"aero_drag", "extra air drag F = -c vx|vx|",
       {{"aero_drag_kgpm", &E::aero_drag_kgpm, -0.05, 3.0, 0.1, "N s^2/m^2"}}, {}, false},
      {"rolling_resistance", "extra rolling resistance F = -(F0 tanh(vx/0.5) + b vx)",
       {{"rolling_force_N", &E::rolling_force_N, -10.0, 60.0, 2.0, "N"},
        {"rolling_viscous_Nspm", &E::rolling_viscous_Nspm, -5.0, 30.0, 1.0, "N s/m"}}, {}, false},
      {"steer_delay", "pure delay of the steering command",
       {{"steer_delay_s", &E::steer_delay_s, 0.0, 0.4, 0.05, "s"}}, {0.03, 0.06, 0.1, 0.15, 0.25}, false},
      {"throttle_delay", "pure delay of the throttle command",
       {{"throttle_delay_s", &E::throttle_delay_s, 0.0, 0.4, 0.05, "s"}}, {0.03, 0.06, 0.1, 0.15, 0.25}, false},
      {"steer_lag", "first-order steering actuator",
       {{"steer_lag_s", &E::steer_lag_s, 0.0, 0.6, 0.05, "s"}}, {0.03, 0.06, 0.1, 0.15, 0.25}, false},
      {"throttle_lag", "first-order throttle / motor response",
       {{"throttle_lag_s", &E::throttle_lag_s, 0.0, 1.0, 0.05, "s"}}, {0.03, 0.06, 0.1, 0.2, 0.4}, false},
      {"steer_offset", "steering bias (trim)",
       {{"steer_offset", &E::steer_offset, -0.4, 0.4, 0.02, "1 (normalised steer)"}}, {}, false},
      {"steer_gain", "steering scale (servo / linkage gain)",
       {{"steer_gain", &E::steer_gain, 0.3, 2.0, 0.1, "1"}}, {0.7, 1.0, 1.3}, false},
      {"throttle_offset", "throttle bias / motor dead band",
       {{"throttle_offset", &E::throttle_offset, -0.4, 0.4, 0.02, "1 (normalised throttle)"}}, {}, false},
      {"tire_saturation", "tyre friction limit (Pacejka peak D x k) and cornering stiffness (x s)",
       {{"tyre_peak_scale", &E::tyre_peak_scale, 0.3, 3.0, 0.1, "1"},
        {"tyre_stiffness_scale", &E::tyre_stiffness_scale, 0.2, 5.0, 0.1, "1"}}, {0.6, 1.0, 1.4}, false},
      {"friction_change", "grip (whole friction curve) x g from time t_change on",
       {{"grip_change_time_s", &E::grip_change_time_s, 0.0, 1e9, 1.0, "s"},
        {"grip_scale", &E::grip_scale, 0.3, 3.0, 0.1, "1"}}, {}, true},
      {"load_transfer", "pitch load transfer: CG height h + dh",
       {{"cg_height_delta_m", &E::cg_height_delta_m, -0.115, 0.12, 0.02, "m"}}, {}, false},
      {"motor_voltage_sag", "drive falls with current: throttle u - k max(u,0)^2",
       {{"voltage_sag", &E::voltage_sag, 0.0, 0.9, 0.05, "1"}}, {}, false},
      {"road_grade", "tilted ground plane z = gx x + gy y",
       {{"grade_x", &E::grade_x, -0.3, 0.3, 0.01, "1 (dz/dx)"},
        {"grade_y", &E::grade_y, -0.3, 0.3, 0.01, "1 (dz/dy)"}}, {}, false},
  };
  return lib;
}

const EffectSpec& effect_spec(const std::string& id) {
  std::string ids;
  for (const auto& e : effect_library()) {
    if (e.id == id) return e;
    ids += (ids.empty() ? "" : ", ") + e.id;
  }
  throw Error("unknown effect '" + id + "' (valid: " + ids + ")");
}

}  // namespace mppi::diagnose
