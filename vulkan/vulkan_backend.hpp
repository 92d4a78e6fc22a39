#pragma once
// The Vulkan compute backend: the same MPPI as the CPU backend on any Vulkan 1.1 device.
// GLSL shaders in vulkan/shaders/ (compiled to SPIR-V at build time) roll out any model whose
// descriptor declares a GPU twin (vulkan/shaders/models/<kernel>.glsl) under the AutoRally cost,
// draw the Philox noise on the device and form the weighted update there. Buffers are
// allocated once per (K, T), descriptor sets written once, two command buffers recorded once
// and replayed; per step only a small uniform buffer and the T x nu plan are written.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "dynamics/autorally_nn.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "dynamics/single_track.hpp"
#include "factory/gpu_twin.hpp"
#include "mppi/backend.hpp"

namespace mppi::vulkan {

struct DeviceInfo {
  int index = 0;          // position in vkEnumeratePhysicalDevices
  std::string name;       // e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string type;       // discrete-gpu | integrated-gpu | virtual-gpu | cpu | other
  bool is_cpu = false;    // a CPU implementation (lavapipe, SwiftShader)
  std::uint32_t api_version = 0;
};

// What the machine offers. Never throws; a missing loader or a failing instance gives
// available = false and the reason.
struct Probe {
  bool available = false;
  std::string error;
  std::vector<DeviceInfo> devices;
};
Probe probe();

// Device choice. The environment variable MPPI_VULKAN_DEVICE (an index, or a part of the
// device name, case-insensitive) picks one explicitly, a CPU device included. Otherwise the
// first discrete GPU, then integrated, virtual, other; a CPU device only if allow_cpu.
// Returns the index into probe.devices, or -1 with the reason in *why.
int pick_device(const Probe& probe, bool allow_cpu, std::string* why);

// A model as the shaders see it: its kernel, state size and parameter floats, made from the
// model's descriptor (factory/gpu_twin.hpp).
using TwinModel = GpuModel;
// The GPU twin of a model, or nullopt and why (e.g. a network of another shape).
template <class M>
std::optional<TwinModel> twin_of(const M& model, std::string* why) {
  return gpu_twin_of(model, why);
}

class Context;  // instance, device, queue (vulkan_context.cpp)

class VulkanBackend final : public Backend {
 public:
  // Builds everything for (K = num_samples, T = horizon) on device `device_index` (of probe())
  // and runs each pipeline once (lavapipe compiles shaders at the first dispatch). Throws
  // mppi::Error if the device cannot be used.
  VulkanBackend(const TwinModel& model, const AutoRallyCost& cost, int num_samples, int horizon,
                float dt_s, int device_index);
  ~VulkanBackend() override;
  VulkanBackend(const VulkanBackend&) = delete;
  VulkanBackend& operator=(const VulkanBackend&) = delete;

  const char* name() const override { return "vulkan"; }
  const RolloutShape& shape() const override { return shape_; }
  const std::string& device_name() const { return device_name_; }
  bool device_is_cpu() const { return device_is_cpu_; }

  void rollout(std::span<const float> x0, std::span<const float> controls,
               std::span<float> costs) override;
  bool has_iterate() const override { return true; }
  bool supports_actuators() const override { return true; }
  void iterate(const IterationInput& in, IterationOutput& out) override;
  std::span<const float> sampled_controls() const override;
  bool set_cost_param(std::string_view key, double value, std::string* why) override;
  bool set_cost_map(std::shared_ptr<const CostMap> map, std::string* why) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  RolloutShape shape_;
  std::string device_name_;
  bool device_is_cpu_ = false;
};

}  // namespace mppi::vulkan
