#pragma once
// Shared by the Vulkan tests: find a Vulkan device (lavapipe counts) or say why there is none.
// When lavapipe's ICD file is installed (CI installs mesa-vulkan-drivers), a missing device is
// a failure, not a skip: the tests must not pass silently on a broken Vulkan set-up.
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>

#include "vulkan/vulkan_backend.hpp"

namespace mppi::test {

inline bool lavapipe_installed() {
  for (const char* dir : {"/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d"}) {
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec))
      if (e.path().filename().string().rfind("lvp_icd", 0) == 0) return true;
  }
  return false;
}

// Index of the device the tests use (any Vulkan device, CPU ones included), or -1 after a
// WARN saying why (and a failure if lavapipe is installed but unusable).
inline int vulkan_test_device() {
  static const vulkan::Probe probe = vulkan::probe();
  std::string why;
  const int index = vulkan::pick_device(probe, /*allow_cpu=*/true, &why);
  if (index < 0) {
    if (lavapipe_installed()) FAIL("lavapipe is installed but no Vulkan device works: " << why);
    WARN("Vulkan test not run: " << why);
  }
  return index;
}

}  // namespace mppi::test
