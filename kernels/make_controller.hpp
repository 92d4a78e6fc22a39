#pragma once
// make_controller(model, cost, options, choice, &report): a Controller on the backend asked
// for, falling back to the CPU backend (never failing) when Vulkan cannot be used, and saying
// which backend runs and why.
//   auto   -> a real GPU through Vulkan (discrete first), else the CPU backend
//   cpu    -> the CPU backend
//   vulkan -> any Vulkan device, a CPU one (lavapipe) included, else the CPU backend
// MPPI_VULKAN_DEVICE=<index or part of the name> picks the Vulkan device (for auto too).
// GPU twins exist for KinematicBicycle, AutoRallyNetwork (3 layers tanh-tanh-linear) and
// SingleTrack under AutoRallyCost; any other model or cost runs on the CPU.
#include <cstdlib>
#include <memory>
#include <string>
#include <type_traits>

#include "kernels/vulkan_backend.hpp"
#include "mppi/backend_choice.hpp"
#include "mppi/controller.hpp"

namespace mppi {

template <class D, class C>
inline constexpr bool kHasGpuTwin =
    std::is_same_v<C, AutoRallyCost> &&
    (std::is_same_v<D, KinematicBicycle> || std::is_same_v<D, AutoRallyNetwork> ||
     std::is_same_v<D, SingleTrack>);

namespace detail {
// The Vulkan backend for (model, cost), or nullptr and why.
template <class D, class C>
std::unique_ptr<Backend> try_vulkan_backend(const D& model, const C& cost,
                                            const ControllerOptions& options, bool allow_cpu,
                                            BackendReport* report) {
  if constexpr (!kHasGpuTwin<D, C>) {
    report->reason = "this model/cost has no GPU twin (Vulkan runs the kinematic bicycle, the "
                     "AutoRally network and the single-track model with the AutoRally cost)";
    return nullptr;
  } else {
    std::string why;
    const auto twin = vulkan::twin_of(model, &why);
    if (!twin) {
      report->reason = why;
      return nullptr;
    }
    const vulkan::Probe probe = vulkan::probe();
    const int index = vulkan::pick_device(probe, allow_cpu, &why);
    if (index < 0) {
      report->reason = why;
      return nullptr;
    }
    try {
      auto backend = std::make_unique<vulkan::VulkanBackend>(*twin, cost, options.num_samples,
                                                             options.horizon, options.dt_s, index);
      report->device = backend->device_name();
      return backend;
    } catch (const Error& e) {
      report->reason = std::string("Vulkan device '") + probe.devices[index].name +
                       "' could not be used: " + e.what();
      return nullptr;
    }
  }
}
}  // namespace detail

template <Dynamics D, StageCost<D> C>
Controller make_controller(D model, C cost, const ControllerOptions& options,
                           BackendChoice choice, BackendReport* report = nullptr) {
  BackendReport local;
  BackendReport& r = report ? *report : local;
  r = BackendReport{};
  std::string why;
  if (!options.is_valid(D::kNu, &why)) throw Error("ControllerOptions: " + why);
  if (choice != BackendChoice::kCpu) {
    auto backend = detail::try_vulkan_backend(model, cost, options, choice == BackendChoice::kVulkan, &r);
    if (backend) {
      const auto* vk = static_cast<const vulkan::VulkanBackend*>(backend.get());
      r.backend = "vulkan";
      const char* env = std::getenv("MPPI_VULKAN_DEVICE");
      r.reason = std::string(choice == BackendChoice::kAuto ? "auto" : "asked for Vulkan") +
                 (env && *env ? std::string(": MPPI_VULKAN_DEVICE=") + env + " picked the device"
                              : std::string(": the best Vulkan device")) +
                 (vk->device_is_cpu() ? "; it is a CPU implementation (e.g. lavapipe): correct but "
                                        "slower than the CPU backend"
                                      : "");
      return Controller(std::move(backend), options);
    }
    r.reason = std::string(choice == BackendChoice::kAuto ? "auto" : "asked for Vulkan, falling back") +
               ": " + r.reason + "; using the CPU backend";
  } else {
    r.reason = "asked for the CPU backend";
  }
  r.backend = "cpu";
  r.device.clear();
  return make_cpu_controller(std::move(model), std::move(cost), options);
}

}  // namespace mppi
