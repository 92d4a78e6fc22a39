#pragma once
// make_controller(model, cost, options, choice, &report): a Controller on the backend asked
// for, falling back to the CPU backend (never failing) when no other backend can run it, and
// saying which backend runs and why. A controller on a GPU backend falls back to the CPU
// backend when the GPU fails while it runs (Controller::set_fallback_backend).
//   auto   -> a real GPU (discrete first) through a registered GPU backend, else the CPU backend
//   cpu    -> the CPU backend
//   vulkan -> any Vulkan device, a CPU one (lavapipe) included, else the CPU backend
// GPU backends (vulkan/) register themselves when linked (factory/backend_registry.hpp); a model
// runs on them if its descriptor declares a GPU twin (dynamics/models/*.hpp) and the cost is
// the AutoRally cost. MPPI_VULKAN_DEVICE=<index or part of the name> picks the Vulkan device.
#include <string>
#include <type_traits>
#include <utility>

#include "factory/backend_registry.hpp"
#include "factory/gpu_twin.hpp"
#include "mppi/backend_choice.hpp"
#include "mppi/controller.hpp"

namespace mppi {

template <Dynamics D, StageCost<D> C>
Controller make_controller(D model, C cost, const ControllerOptions& options, BackendChoice choice,
                           BackendReport* report = nullptr) {
  BackendReport local;
  BackendReport& r = report ? *report : local;
  r = BackendReport{};
  std::string why;
  if (!options.is_valid(D::kNu, &why)) throw Error("ControllerOptions: " + why);
  if (choice != BackendChoice::kCpu) {
    const char* asked = choice == BackendChoice::kAuto ? "auto" : "asked for Vulkan, falling back";
    if constexpr (!std::is_same_v<C, AutoRallyCost>) {
      r.reason = "this model/cost has no GPU twin (GPU backends run the AutoRally cost)";
    } else {
      const auto twin = gpu_twin_of(model, &why);
      if (!twin) {
        r.reason = why.find("GPU twin") != std::string::npos ? why : "no GPU twin: " + why;
      } else if (backend_factories().empty()) {
        r.reason = "built without a GPU backend (vulkan/)";
      } else {
        for (const BackendFactory& factory : backend_factories()) {
          auto backend = factory.make(*twin, cost, options, choice == BackendChoice::kVulkan, &r);
          if (backend) {
            r.backend = factory.name;
            r.reason = factory.describe(*backend, choice);
            // The tube variants linearise the model on the CPU (64 lanes, one thread), beside
            // the GPU's sampling.
            std::unique_ptr<Backend> feedback;
            if (options.variant != ControllerVariant::kPlain)
              feedback = std::make_unique<CpuBackend<D, C>>(model, cost, 64, options.horizon, options.dt_s, 1,
                                                            options.schedule);
            Controller controller(std::move(backend), options, std::move(feedback));
            // A GPU can fail while running (a lost device): step() then goes on on the CPU.
            controller.set_fallback_backend([model, cost, options]() -> std::unique_ptr<Backend> {
              return std::make_unique<CpuBackend<D, C>>(model, cost, options.num_samples, options.horizon,
                                                        options.dt_s, options.num_threads, options.schedule);
            });
            return controller;
          }
        }
      }
    }
    r.reason = std::string(asked) + ": " + r.reason + "; using the CPU backend";
  } else {
    r.reason = "asked for the CPU backend";
  }
  r.backend = "cpu";
  r.device.clear();
  return make_cpu_controller(std::move(model), std::move(cost), options);
}

}  // namespace mppi
