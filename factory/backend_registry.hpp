#pragma once
// Rollout backends other than the CPU one (vulkan/: Vulkan) register themselves here when
// their library is linked (a static registrar in the backend's library; the library's link
// interface keeps that object in the program). make_controller() (factory/make_controller.hpp)
// asks them in registration order.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "factory/gpu_twin.hpp"
#include "mppi/backend.hpp"
#include "mppi/backend_choice.hpp"
#include "mppi/controller_options.hpp"

namespace mppi {

struct BackendFactory {
  const char* name;  // "vulkan"
  // A backend for (model twin, cost) or nullptr with the reason in report->reason; never throws.
  // allow_cpu_device: a CPU implementation of the API (lavapipe) may be used. Fills
  // report->device on success.
  std::function<std::unique_ptr<Backend>(const GpuModel&, const AutoRallyCost&, const ControllerOptions&,
                                         bool allow_cpu_device, BackendReport*)>
      make;
  // The reason text when the backend was chosen ("auto: the best Vulkan device ...").
  std::function<std::string(const Backend&, BackendChoice)> describe;
};

inline std::vector<BackendFactory>& backend_factories() {
  static std::vector<BackendFactory> factories;
  return factories;
}

// Called by a backend library's static registrar.
inline bool register_backend(BackendFactory factory) {
  backend_factories().push_back(std::move(factory));
  return true;
}

}  // namespace mppi
