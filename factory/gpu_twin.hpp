#pragma once
// A model as a GPU backend sees it, built from the model's descriptor (dynamics/models/*.hpp):
// the kernel id (vulkan/shaders/models/<kernel>.glsl), the state size, and the floats of the
// parameter block in the order of the descriptor's gpu_fields() (whose names the build turns
// into the GLSL #defines the kernel reads), then the descriptor's tail arrays.
#include <optional>
#include <string>
#include <vector>

#include "dynamics/model_registry.hpp"

namespace mppi {

struct GpuModel {
  std::string kernel;            // vulkan/shaders/models/<kernel>.glsl
  int num_states = 0;
  int constant_a = 1, constant_b = 1;  // shader constants of the kernel (e.g. hidden sizes)
  std::vector<float> params;     // named floats (gpu_fields order), then the tail
};

// The GPU twin of a registered model with one, or nullopt and why.
template <class M>
std::optional<GpuModel> gpu_twin_of(const M& model, std::string* why) {
  using D = DescriptorOf<M>;
  if constexpr (std::is_void_v<D>) {
    if (why) *why = "this model is not a registered model of the library, so it has no GPU twin";
    return std::nullopt;
  } else if constexpr (!HasGpuTwin<D>) {
    if (why) *why = std::string("the ") + D::kName + " model has no GPU twin";
    return std::nullopt;
  } else {
    GpuModel twin;
    twin.kernel = D::kGpuKernel;
    twin.num_states = M::kNx;
    for (const auto& field : D::gpu_fields()) twin.params.push_back(field.value(model));
    if constexpr (HasGpuTail<D>) {
      GpuTail tail;
      if (!D::gpu_tail(model, tail, why)) return std::nullopt;
      twin.constant_a = tail.constant_a;
      twin.constant_b = tail.constant_b;
      twin.params.insert(twin.params.end(), tail.floats.begin(), tail.floats.end());
    }
    return twin;
  }
}

}  // namespace mppi
