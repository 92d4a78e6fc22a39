#pragma once
// Which backend runs the rollouts: asked for by the user (mppi-sim --backend, the API), and
// what was actually used and why (factory/make_controller.hpp does the choosing).
#include <string>

#include "base/error.hpp"

namespace mppi {

enum class BackendChoice {
  kAuto,    // a real GPU through Vulkan if there is one, else the CPU backend
  kCpu,     // the CPU backend
  kVulkan,  // Vulkan, a CPU Vulkan device (lavapipe) included; the CPU backend if none works
};

// "auto" | "cpu" | "vulkan"; throws mppi::Error naming the bad value otherwise.
inline BackendChoice parse_backend_choice(const std::string& text) {
  if (text == "auto") return BackendChoice::kAuto;
  if (text == "cpu") return BackendChoice::kCpu;
  if (text == "vulkan") return BackendChoice::kVulkan;
  throw Error("unknown backend '" + text + "' (valid: auto, cpu, vulkan)");
}

inline const char* to_string(BackendChoice c) {
  switch (c) {
    case BackendChoice::kAuto: return "auto";
    case BackendChoice::kCpu: return "cpu";
    case BackendChoice::kVulkan: return "vulkan";
  }
  return "?";
}

// What make_controller() chose.
struct BackendReport {
  std::string backend;  // "cpu" or "vulkan"
  std::string device;   // Vulkan device name (empty for the CPU backend)
  std::string reason;   // why this backend, in one sentence
};

}  // namespace mppi
