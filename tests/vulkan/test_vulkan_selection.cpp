// Backend selection: --backend auto|cpu|vulkan, the device rules (a CPU Vulkan device only
// when asked for; MPPI_VULKAN_DEVICE picks one), and the fallbacks that must never crash.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>

#include "costs/autorally_cost.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "factory/make_controller.hpp"
#include "vulkan/vulkan_backend.hpp"
#include "tests/mppi/linear_system.hpp"
#include "vulkan/vulkan_test_util.hpp"

namespace {

mppi::vulkan::DeviceInfo device(int index, const std::string& name, const std::string& type) {
  mppi::vulkan::DeviceInfo d;
  d.index = index;
  d.name = name;
  d.type = type;
  d.is_cpu = type == "cpu";
  d.api_version = (1u << 22) | (3u << 12);  // Vulkan 1.3
  return d;
}

// Sets an environment variable for one scope.
struct ScopedEnv {
  std::string name;
  std::string old;
  bool had = false;
  ScopedEnv(const char* n, const char* value) : name(n) {
    if (const char* o = std::getenv(n)) {
      had = true;
      old = o;
    }
    if (value) setenv(n, value, 1);
    else unsetenv(n);
  }
  ~ScopedEnv() {
    if (had) setenv(name.c_str(), old.c_str(), 1);
    else unsetenv(name.c_str());
  }
};

std::shared_ptr<const mppi::CostMap> flat_map() {
  return std::make_shared<const mppi::CostMap>(-50.f, 50.f, -50.f, 50.f, 1.f,
                                               std::vector<float>(100 * 100, 0.f));
}

}  // namespace

TEST_CASE("backend names parse, and a bad one is an error naming it", "[vulkan][selection]") {
  CHECK(mppi::parse_backend_choice("auto") == mppi::BackendChoice::kAuto);
  CHECK(mppi::parse_backend_choice("cpu") == mppi::BackendChoice::kCpu);
  CHECK(mppi::parse_backend_choice("vulkan") == mppi::BackendChoice::kVulkan);
  CHECK_THROWS_WITH(mppi::parse_backend_choice("cuda"), Catch::Contains("'cuda'"));
}

TEST_CASE("device choice: GPUs first, a CPU device only when allowed, the variable decides",
          "[vulkan][selection]") {
  const ScopedEnv no_env("MPPI_VULKAN_DEVICE", nullptr);
  mppi::vulkan::Probe p;
  p.available = true;
  p.devices = {device(0, "llvmpipe (LLVM 15)", "cpu"), device(1, "Intel UHD", "integrated-gpu"),
               device(2, "NVIDIA RTX 4090", "discrete-gpu")};
  std::string why;
  CHECK(mppi::vulkan::pick_device(p, false, &why) == 2);
  p.devices.pop_back();
  CHECK(mppi::vulkan::pick_device(p, false, &why) == 1);
  p.devices.pop_back();
  CHECK(mppi::vulkan::pick_device(p, false, &why) == -1);  // only lavapipe: not for auto
  CHECK_THAT(why, Catch::Contains("llvmpipe") && Catch::Contains("--backend vulkan"));
  CHECK(mppi::vulkan::pick_device(p, true, &why) == 0);    // asked for Vulkan: lavapipe is fine

  p.devices = {device(0, "llvmpipe (LLVM 15)", "cpu"), device(1, "NVIDIA RTX 4090", "discrete-gpu")};
  {
    const ScopedEnv env("MPPI_VULKAN_DEVICE", "LLVMpipe");
    CHECK(mppi::vulkan::pick_device(p, false, &why) == 0);  // named explicitly
  }
  {
    const ScopedEnv env("MPPI_VULKAN_DEVICE", "1");
    CHECK(mppi::vulkan::pick_device(p, true, &why) == 1);
  }
  {
    const ScopedEnv env("MPPI_VULKAN_DEVICE", "7");
    CHECK(mppi::vulkan::pick_device(p, true, &why) == -1);
    CHECK_THAT(why, Catch::Contains("MPPI_VULKAN_DEVICE=7"));
  }
  mppi::vulkan::Probe none;
  none.error = "no Vulkan loader";
  CHECK(mppi::vulkan::pick_device(none, true, &why) == -1);
  CHECK(why == "no Vulkan loader");
}

TEST_CASE("make_controller reports the backend it chose and falls back to the CPU",
          "[vulkan][selection]") {
  const ScopedEnv no_env("MPPI_VULKAN_DEVICE", nullptr);
  mppi::ControllerOptions o;
  o.num_samples = 100;
  o.horizon = 20;
  const mppi::AutoRallyCost cost(flat_map());
  mppi::BackendReport r;

  auto cpu = mppi::make_controller(mppi::KinematicBicycle{}, cost, o, mppi::BackendChoice::kCpu, &r);
  CHECK(r.backend == "cpu");
  CHECK(std::string(cpu.backend().name()) == "cpu");

  // A model without a GPU twin: Vulkan asked for, the CPU runs it, and says why.
  mppi::ControllerOptions o1 = o;
  o1.noise_std = {1.f};
  o1.control_min = {-1.f};
  o1.control_max = {1.f};
  o1.safe_control = {0.f};
  auto di = mppi::make_controller(mppi::test::DoubleIntegrator{}, mppi::test::QuadraticCost{}, o1,
                                  mppi::BackendChoice::kVulkan, &r);
  CHECK(r.backend == "cpu");
  CHECK_THAT(r.reason, Catch::Contains("no GPU twin"));
  CHECK(std::string(di.backend().name()) == "cpu");

  // auto takes a real GPU only; vulkan takes any device.
  const mppi::vulkan::Probe probe = mppi::vulkan::probe();
  std::string why;
  const bool has_gpu = mppi::vulkan::pick_device(probe, false, &why) >= 0;
  auto a = mppi::make_controller(mppi::KinematicBicycle{}, cost, o, mppi::BackendChoice::kAuto, &r);
  INFO("auto: " << r.backend << " (" << r.reason << ")");
  CHECK(r.backend == (has_gpu ? "vulkan" : "cpu"));
  CHECK(std::string(a.backend().name()) == r.backend);
  CHECK(!r.reason.empty());

  if (mppi::test::vulkan_test_device() < 0) return;
  auto v = mppi::make_controller(mppi::KinematicBicycle{}, cost, o, mppi::BackendChoice::kVulkan, &r);
  INFO("vulkan: " << r.backend << " (" << r.reason << ")");
  CHECK(r.backend == "vulkan");
  CHECK(!r.device.empty());
  CHECK(std::string(v.backend().name()) == "vulkan");
}

TEST_CASE("no Vulkan driver: a clear reason and the CPU backend, not a crash", "[vulkan][selection]") {
  // The loader reads these at instance creation: pointing them at nothing leaves no driver.
  const ScopedEnv icd("VK_ICD_FILENAMES", "/nonexistent/mppi_no_icd.json");
  const ScopedEnv drivers("VK_DRIVER_FILES", "/nonexistent/mppi_no_icd.json");
  const mppi::vulkan::Probe p = mppi::vulkan::probe();
  CHECK_FALSE(p.available);
  CHECK(!p.error.empty());
  mppi::ControllerOptions o;
  o.num_samples = 64;
  o.horizon = 10;
  mppi::BackendReport r;
  auto c = mppi::make_controller(mppi::KinematicBicycle{}, mppi::AutoRallyCost(flat_map()), o,
                                 mppi::BackendChoice::kVulkan, &r);
  CHECK(r.backend == "cpu");
  CHECK_THAT(r.reason, Catch::Contains("falling back") && Catch::Contains(p.error));
  const float x0[7] = {0, 0, 0, 1, 0, 0, 0};
  CHECK(std::isfinite(c.step(x0)[0]));
}
