#pragma once
// AutoRally's basis-function model (dynamics/autorally_bf.hpp) as the registry knows it.
#include <string>
#include <vector>

#include "dynamics/autorally_bf.hpp"
#include "dynamics/model_descriptor.hpp"

namespace mppi::models {

struct AutoRallyBasisFunctions : WeightsFileDescriptor<AutoRallyBasisFunctions, AutoRallyBasisFunctionModel> {
  static constexpr const char* kName = "autorally-bf";
  static constexpr const char* kSummary = "the AutoRally car's basis-function model (25 hand-made features, fitted weights)";
  static constexpr const char* kDefaultFile = "autorally/models/basis_function_09_12_2018.npz";

  // GPU twin: vulkan/shaders/models/autorally_bf.glsl reads W (4 x 25, row-major) after the
  // named floats.
  static constexpr const char* kGpuKernel = "autorally_bf";
  static std::vector<GpuField<Model>> gpu_fields() { return {}; }
  static bool gpu_tail(const Model& m, GpuTail& tail, std::string*) {
    tail.floats.assign(m.weights().begin(), m.weights().end());
    return true;
  }
};
MPPI_REGISTER_MODEL(AutoRallyBasisFunctions);

}  // namespace mppi::models
