#pragma once
// The registered models that sysid can estimate and calibrate (sysid/vehicle_model_spec.hpp), by
// name: one traits type per model in EstimableModels and lookups over it. mppi-fit estimate,
// mppi-fit calibrate and the Python bindings find a model's spec, files and defaults here.
//
// Each traits type E gives
//   using Descriptor;                                the registered model (dynamics/models/)
//   static constexpr const char* kName;              Descriptor::kName
//   static constexpr const char* kEstimationFile;    base parameters of an estimation, relative
//                                                    to the data folder
//   static constexpr const char* kDragParam;         the parameter holding the aerodynamic drag
//   static constexpr bool kActuatorTerms;            its spec estimates the actuator effects
//                                                    (steer_lag_s, ...) too
//   using Params; static Params load_params(path);
//   static std::vector<std::string> param_names();          all estimable parameters
//   static std::vector<std::string> default_estimated();    the usual set to estimate
//   static VehicleModelSpec spec(const Params&, names, keep_wheelbase);
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "base/error.hpp"
#include "base/type_list.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/vehicle_params.hpp"
#include "sysid/vehicle_model_spec.hpp"

namespace mppi::sysid {

struct EstimableSingleTrack {
  using Descriptor = models::SingleTrackModel;
  using Params = SingleTrackParams;
  static constexpr const char* kName = Descriptor::kName;
  static constexpr const char* kEstimationFile = Descriptor::kDefaultFile;
  static constexpr const char* kDragParam = "aero_drag_kgpm";
  static constexpr bool kActuatorTerms = true;
  static Params load_params(const std::string& path) { return load_single_track_params(path); }
  static std::vector<std::string> param_names() { return single_track_param_names(); }
  static std::vector<std::string> default_estimated() {
    return {"yaw_inertia_kgm2", "cg_to_front_axle_m", "tyre.B", "tyre.C", "tyre.D"};
  }
  static VehicleModelSpec spec(const Params& base, const std::vector<std::string>& estimated,
                               bool keep_wheelbase = false) {
    return single_track_spec(base, estimated, keep_wheelbase);
  }
};

struct EstimableDoubleTrack {
  using Descriptor = models::DoubleTrackModel;
  using Params = DoubleTrackParams;
  static constexpr const char* kName = Descriptor::kName;
  static constexpr const char* kEstimationFile = Descriptor::kDefaultFile;
  static constexpr const char* kDragParam = "aero_drag_kgpm";
  static constexpr bool kActuatorTerms = false;
  static Params load_params(const std::string& path) { return load_double_track_params(path); }
  static std::vector<std::string> param_names() { return double_track_param_names(); }
  static std::vector<std::string> default_estimated() {
    return {"mass_kg", "yaw_inertia_kgm2", "rear_wheel_inertia_kgm2", "cg_height_m",
            "cg_to_front_axle_m", "tyre.B", "tyre.C", "tyre.D"};
  }
  static VehicleModelSpec spec(const Params& base, const std::vector<std::string>& estimated,
                               bool keep_wheelbase = false) {
    return double_track_spec(base, estimated, keep_wheelbase);
  }
};

struct EstimableFullVehicle {
  using Descriptor = models::FullVehicleModel;
  using Params = FullVehicleParams;
  static constexpr const char* kName = Descriptor::kName;
  // The paper's values: the shipped default file is the calibrated one.
  static constexpr const char* kEstimationFile = "config/autorally_full_vehicle_uncalibrated.yaml";
  // Its drag is drag_coefficient (x air density x frontal area / 2).
  static constexpr const char* kDragParam = "drag_coefficient";
  static constexpr bool kActuatorTerms = false;
  static Params load_params(const std::string& path) { return load_full_vehicle_params(path); }
  static std::vector<std::string> param_names() { return full_vehicle_param_names(); }
  static std::vector<std::string> default_estimated() {
    return {"mass_kg", "yaw_inertia_kgm2", "rear_wheel_inertia_kgm2", "cg_height_m", "cg_to_front_axle_m",
            "tyre.B", "tyre.C", "tyre.D", "front_damper_Nspm", "rear_damper_Nspm"};
  }
  static VehicleModelSpec spec(const Params& base, const std::vector<std::string>& estimated,
                               bool keep_wheelbase = false) {
    return full_vehicle_spec(base, estimated, keep_wheelbase);
  }
};

using EstimableModels = TypeList<EstimableSingleTrack, EstimableDoubleTrack, EstimableFullVehicle>;

// The estimable model names, in EstimableModels order.
inline std::vector<std::string> estimable_model_names() {
  std::vector<std::string> names;
  for_each_type(EstimableModels{}, [&]<class E>() { names.emplace_back(E::kName); });
  return names;
}

// "single-track, double-track or full-vehicle".
inline std::string estimable_model_choices() {
  const std::vector<std::string> names = estimable_model_names();
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return out;
}

// f.template operator()<E>() for the estimable model called `name`; returns what f returns.
// Throws mppi::Error "<what> expects single-track, double-track or full-vehicle, got '<name>'"
// for any other name.
template <class F>
auto with_estimable_model(std::string_view name, F&& f, const std::string& what = "model") {
  auto unknown = [&] {
    return Error(what + " expects " + estimable_model_choices() + ", got '" + std::string(name) + "'");
  };
  using R = decltype(f.template operator()<FrontOf<EstimableModels>>());
  if constexpr (std::is_void_v<R>) {
    if (!visit_by_name(EstimableModels{}, name, f)) throw unknown();
  } else {
    std::optional<R> result;
    if (!visit_by_name(EstimableModels{}, name, f, result)) throw unknown();
    return R(std::move(*result));
  }
}

}  // namespace mppi::sysid
