// The Vulkan backend enters the backend registry (factory/backend_registry.hpp) when the program
// starts: make_controller() then offers it for every model with a GPU twin. The exported symbol
// below is what the library's link interface names (--undefined) so that this object is linked.
#include <cstdlib>
#include <memory>
#include <string>

#include "base/error.hpp"
#include "factory/backend_registry.hpp"
#include "vulkan/vulkan_backend.hpp"

namespace mppi::vulkan {
namespace {

std::unique_ptr<Backend> make_vulkan(const GpuModel& model, const AutoRallyCost& cost,
                                     const ControllerOptions& options, bool allow_cpu_device,
                                     BackendReport* report) {
  std::string why;
  const Probe p = probe();
  const int index = pick_device(p, allow_cpu_device, &why);
  if (index < 0) {
    report->reason = why;
    return nullptr;
  }
  try {
    auto backend = std::make_unique<VulkanBackend>(model, cost, options.num_samples, options.horizon,
                                                   options.dt_s, index);
    report->device = backend->device_name();
    return backend;
  } catch (const std::exception& e) {
    report->reason = std::string("Vulkan device '") + p.devices[index].name + "' could not be used: " + e.what();
    return nullptr;
  }
}

std::string describe_vulkan(const Backend& backend, BackendChoice choice) {
  const auto& vk = static_cast<const VulkanBackend&>(backend);
  const char* env = std::getenv("MPPI_VULKAN_DEVICE");
  return std::string(choice == BackendChoice::kAuto ? "auto" : "asked for Vulkan") +
         (env && *env ? std::string(": MPPI_VULKAN_DEVICE=") + env + " picked the device"
                      : std::string(": the best Vulkan device")) +
         (vk.device_is_cpu() ? "; it is a CPU implementation (e.g. lavapipe): correct but slower than "
                               "the CPU backend"
                             : "");
}

const bool kRegistered = register_backend({"vulkan", &make_vulkan, &describe_vulkan});

}  // namespace
}  // namespace mppi::vulkan

extern "C" {
// Named by the library's INTERFACE link options; reading kRegistered keeps the registrar.
const bool* mppi_vulkan_backend_registered = &mppi::vulkan::kRegistered;
}
