// A GPU lost in the middle of a lap: the closed loop on the Vulkan backend (lavapipe in CI)
// with a device loss injected after 100 control steps must go on on the CPU backend, finish
// the lap without a crash, and record the switch (step, time, reason) in summary.json and in
// log.csv's backend_switches column.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "mppi/controller.hpp"
#include "sim/closed_loop.hpp"
#include "sim/recording.hpp"
#include "vulkan/vulkan_test_util.hpp"

TEST_CASE("a lap on Vulkan survives a lost device by going on on the CPU backend", "[vulkan][closed_loop][fault]") {
  if (mppi::test::vulkan_test_device() < 0) return;
  const std::string out = (std::filesystem::temp_directory_path() /
                           ("mppi_device_loss_" + std::to_string(::getpid()))).string();
  mppi::sim::ClosedLoopConfig c;
  c.track = "gazebo";
  c.model = "autorally-nn";
  c.plant = "single-track";
  c.target_speed_mps = 5.0;
  c.laps = 1;
  c.controller.num_samples = 384;
  c.controller.horizon = 60;
  c.controller.seed = 3;
  c.progress = false;
  c.backend = mppi::BackendChoice::kVulkan;
  c.inject_device_loss_at_step = 100;
  c.out_dir = out;
  mppi::BackendReport report;
  c.backend_report = &report;
  const auto summary = mppi::sim::run_closed_loop(c);

  REQUIRE(report.backend == "vulkan");
  CHECK(summary.backend == "vulkan");
  CHECK(summary.laps_completed == 1);
  CHECK(summary.crashes == 0);
  CHECK(summary.failed_steps == 1);  // only the step at which the device was lost
  REQUIRE(summary.backend_switches.size() == 1);
  const auto& sw = summary.backend_switches[0];
  CHECK(sw.control_step == 100);
  CHECK(sw.time_s == Approx(100 * c.controller.dt_s).margin(1e-6));
  CHECK(sw.from == "vulkan");
  CHECK(sw.to == "cpu");
  CHECK_THAT(sw.reason, Catch::Contains("device lost"));

  std::ifstream f(out + "/summary.json");
  const auto j = nlohmann::json::parse(f);
  CHECK(j.at("backend") == "vulkan");
  REQUIRE(j.at("backend_switches").size() == 1);
  CHECK(j.at("backend_switches")[0].at("control_step") == 100);
  CHECK(j.at("backend_switches")[0].at("to") == "cpu");

  // log.csv: one row per control step; the switch count turns 0 -> 1 at row 100, the failed
  // step's status is kBackendError, and every applied command is finite.
  const auto log = mppi::sim::RecordingReader::read(out + "/log.csv");
  const auto& switches = log.column("backend_switches");
  const auto& status = log.column("step_status");
  REQUIRE(switches.size() > 101);
  CHECK(switches[99] == 0.0);
  CHECK(switches[100] == 1.0);
  CHECK(switches.back() == 1.0);
  CHECK(status[100] == static_cast<double>(mppi::StepStatus::kBackendError));
  for (double steer : log.column("steer")) REQUIRE(std::isfinite(steer));
  std::filesystem::remove_all(out);
}
