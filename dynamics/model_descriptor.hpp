#pragma once
// A dynamics model declared once: its descriptor (one header under dynamics/models/) gives
//   using Model;                                    the VehicleDynamics class
//   static constexpr const char* kName, kSummary;   "single-track", one line for --help
//   static constexpr const char* kDefaultFile;      data file relative to the data folder
//                                                   ("" = built-in defaults)
//   static Model load(const std::string& path);     from a data file; "" = built-in defaults
//   static std::vector<std::string> state_names();  kNx names, the common states first
//   static void from_plant(const Model&, const float* plant_x, int plant_states, float* x);
//                                                   its state from a simulated car's state
// optionally its YAML parameter table, and the table as YAML text (strict reading, as a
// parameter file is read: `source` names the text in errors; writing gives every key)
//   using Params; static std::vector<ParamField> params(Params&); static Model make(const Params&);
//   static Params params_from_yaml(const std::string& text, const std::string& source);
//   static std::string params_to_yaml(const Params&);
// and optionally a GPU twin (vulkan/): the GLSL file vulkan/shaders/models/<kGpuKernel>.glsl
// and the floats of the parameter block it reads, named as the GLSL code names them
//   static constexpr const char* kGpuKernel;
//   static std::vector<GpuField<Model>> gpu_fields();
//   static bool gpu_tail(const Model&, GpuTail& tail, std::string* why);   (optional: arrays
//                                                   after the named floats, shader constants)
// A descriptor may take the usual parts from ParamTableDescriptor or WeightsFileDescriptor
// below by deriving from it. The line MPPI_REGISTER_MODEL(Descriptor) in the header enters it
// into the compile-time list of models (<build>/generated/dynamics/model_list.hpp, collected by
// the build from dynamics/models/*.hpp).
#include <algorithm>
#include <concepts>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "base/error.hpp"
#include "base/param_table.hpp"
#include "base/param_yaml.hpp"
#include "mppi/concepts.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

// One float of a GPU twin's parameter block: the name the GLSL code reads it by (a #define the
// build generates) and how to compute it from the model.
template <class Model>
struct GpuField {
  const char* name;
  float (*value)(const Model&);
};

// What a GPU twin packs after its named floats: raw arrays (e.g. network weights) and up to two
// integer shader constants (specialization constants 2 and 3 of the rollout shader).
struct GpuTail {
  std::vector<float> floats;
  int constant_a = 1, constant_b = 1;
};

template <class D>
concept ModelDescriptor =
    VehicleDynamics<typename D::Model> &&
    requires(const typename D::Model& m, const float* px, float* mx, const std::string& path) {
      { D::kName } -> std::convertible_to<std::string_view>;
      { D::kSummary } -> std::convertible_to<std::string_view>;
      { D::kDefaultFile } -> std::convertible_to<std::string_view>;
      { D::load(path) } -> std::same_as<typename D::Model>;
      { D::state_names() } -> std::same_as<std::vector<std::string>>;
      D::from_plant(m, px, 0, mx);
    };

template <class D>
concept HasParamTable = requires(typename D::Params& p, const std::string& text) {
  { D::params(p) } -> std::same_as<std::vector<ParamField>>;
  { D::make(p) } -> std::same_as<typename D::Model>;
  { D::params_from_yaml(text, text) } -> std::same_as<typename D::Params>;
  { D::params_to_yaml(p) } -> std::same_as<std::string>;
};

template <class D>
concept HasGpuTwin = requires {
  { D::kGpuKernel } -> std::convertible_to<std::string_view>;
  { D::gpu_fields() } -> std::same_as<std::vector<GpuField<typename D::Model>>>;
};

template <class D>
concept HasGpuTail = requires(const typename D::Model& m, GpuTail& t, std::string* why) {
  { D::gpu_tail(m, t, why) } -> std::same_as<bool>;
};

// Names for the common states of mppi/vehicle_state.hpp, in order.
inline std::vector<std::string> common_state_names() {
  return {"x_m", "y_m", "yaw_rad", "vx_mps", "vy_mps", "yaw_rate_radps", "roll_rad"};
}

// The common state names followed by a model's own states.
inline std::vector<std::string> common_state_names_and(std::initializer_list<std::string> own) {
  std::vector<std::string> names = common_state_names();
  names.insert(names.end(), own);
  return names;
}

// The descriptor part of a model built from a YAML parameter table P (param_table(P&)): make()
// from parameters, load() from a file through `load_params` ("" = the built-in defaults), the
// table from YAML text through `read_params` (it names the model in errors and checks the
// conditions between fields) and back.
template <class M, class P, P (*load_params)(const std::string&),
          P (*read_params)(const std::string& text, const std::string& source)>
struct ParamTableDescriptor {
  using Model = M;
  using Params = P;
  static std::vector<ParamField> params(Params& p) { return param_table(p); }
  static Model make(const Params& p) { return Model(p); }
  static Model load(const std::string& path) { return Model(path.empty() ? Params{} : load_params(path)); }
  static Params params_from_yaml(const std::string& text, const std::string& source) {
    return read_params(text, source);
  }
  static std::string params_to_yaml(const Params& p) {
    Params copy = p;  // param_table takes a mutable set: its fields point into it
    return write_param_yaml(param_table(copy));
  }
};

// The descriptor part of a learned model: M::load reads its weights file, which has no built-in
// default; its state is the common state, copied from any plant. Self: the descriptor (its kName
// names the model in the error).
template <class Self, class M>
struct WeightsFileDescriptor {
  using Model = M;
  static Model load(const std::string& path) {
    if (path.empty()) throw Error(std::string("the ") + Self::kName + " model needs its weights file (npz)");
    return Model::load(path);
  }
  static std::vector<std::string> state_names() { return common_state_names(); }
  static void from_plant(const Model&, const float* px, int, float* mx) {
    std::copy(px, px + state::kCommonStates, mx);
  }
};

}  // namespace mppi

#define MPPI_REGISTER_MODEL(Descriptor) \
  static_assert(::mppi::ModelDescriptor<Descriptor>, #Descriptor " is not a complete model descriptor")
