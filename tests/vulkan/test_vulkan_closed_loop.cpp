// mppi-sim's closed loop on the Vulkan backend (lavapipe in CI) against the same run on the
// CPU backend: the AutoRally network drives one lap of the Gazebo oval; both must finish it
// without a crash and in about the same time (the runs are not bit-identical: last-bit
// differences between the backends grow over a closed loop).
#include <catch2/catch.hpp>

#include "sim/closed_loop.hpp"
#include "vulkan/vulkan_test_util.hpp"

TEST_CASE("the closed loop laps the Gazebo oval on Vulkan as on the CPU", "[vulkan][closed_loop]") {
  if (mppi::test::vulkan_test_device() < 0) return;
  mppi::sim::ClosedLoopConfig c;
  c.track = "gazebo";
  c.model = "autorally-nn";
  c.plant = "single-track";
  c.target_speed_mps = 5.0;
  c.laps = 1;
  c.controller.num_samples = 384;  // small, so that lavapipe on 2 cores takes ~20 s
  c.controller.horizon = 60;
  c.controller.seed = 3;
  c.progress = false;

  mppi::BackendReport cpu_report, vk_report;
  c.backend = mppi::BackendChoice::kCpu;
  c.backend_report = &cpu_report;
  const auto cpu = mppi::sim::run_closed_loop(c);
  c.backend = mppi::BackendChoice::kVulkan;
  c.backend_report = &vk_report;
  const auto vk = mppi::sim::run_closed_loop(c);

  CHECK(cpu_report.backend == "cpu");
  REQUIRE(vk_report.backend == "vulkan");
  INFO("CPU lap " << (cpu.lap_times_s.empty() ? 0 : cpu.lap_times_s[0]) << " s, Vulkan ("
                  << vk_report.device << ") lap " << (vk.lap_times_s.empty() ? 0 : vk.lap_times_s[0]) << " s");
  CHECK(cpu.laps_completed == 1);
  CHECK(vk.laps_completed == cpu.laps_completed);
  CHECK(vk.crashes == 0);
  CHECK(cpu.crashes == 0);
  REQUIRE(vk.lap_times_s.size() == 1);
  REQUIRE(cpu.lap_times_s.size() == 1);
  CHECK(vk.lap_times_s[0] == Approx(cpu.lap_times_s[0]).epsilon(0.05));
  CHECK(vk.mean_speed_mps == Approx(cpu.mean_speed_mps).epsilon(0.05));
}
