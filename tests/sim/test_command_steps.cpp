// The run's command steps (RunSummary::mean_abs_steer_step / mean_abs_throttle_step): a closed
// form on a known sequence, and a run's figures recomputed from its log.csv.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "sim/closed_loop.hpp"
#include "sim/command_steps.hpp"
#include "sim/recording.hpp"

using mppi::Control;
using mppi::sim::CommandSteps;

TEST_CASE("command steps: the mean |u_k - u_(k-1)| per channel over consecutive commands", "[sim][summary]") {
  CommandSteps none;
  CHECK(none.mean_abs_steer_step() == 0.0);
  none.add({0.5f, 0.5f});
  CHECK(none.mean_abs_throttle_step() == 0.0);  // one command: no step yet

  CommandSteps steps;
  for (const Control u : {Control{0.f, 0.f}, Control{0.5f, 0.25f}, Control{-0.5f, 0.25f}, Control{-0.25f, -0.75f}})
    steps.add(u);
  CHECK(steps.mean_abs_steer_step() == Approx((0.5 + 1.0 + 0.25) / 3));
  CHECK(steps.mean_abs_throttle_step() == Approx((0.25 + 0.0 + 1.0) / 3));
}

TEST_CASE("command steps: a run's figures are those of the commands in its log.csv", "[sim][summary][closed_loop]") {
  mppi::sim::ClosedLoopConfig config;
  config.track = "gazebo";
  config.model = "single-track";
  config.plant = "single-track";
  config.target_speed_mps = 5.0;
  config.max_time_s = 4.0;
  config.controller.num_samples = 256;
  config.controller.horizon = 50;
  config.controller.seed = 2;
  config.progress = false;
  config.out_dir = (std::filesystem::temp_directory_path() / ("mppi_command_steps_" + std::to_string(::getpid()))).string();
  const mppi::sim::RunSummary summary = mppi::sim::run_closed_loop(config);

  // log.csv: one row per control step, the command sent to the car in `steer` and `throttle`.
  const auto log = mppi::sim::RecordingReader::read(config.out_dir + "/log.csv");
  const auto& steer = log.column("steer");
  const auto& throttle = log.column("throttle");
  REQUIRE(log.rows() > 100);
  double steer_sum = 0.0, throttle_sum = 0.0;
  for (std::size_t i = 1; i < log.rows(); ++i) {
    steer_sum += std::abs(steer[i] - steer[i - 1]);
    throttle_sum += std::abs(throttle[i] - throttle[i - 1]);
  }
  const double steps = static_cast<double>(log.rows() - 1);
  CHECK(summary.mean_abs_steer_step == Approx(steer_sum / steps).margin(1e-5));
  CHECK(summary.mean_abs_throttle_step == Approx(throttle_sum / steps).margin(1e-5));
  CHECK(summary.mean_abs_steer_step > 0.0);  // a controller that drives changes its commands

  std::ifstream in(config.out_dir + "/summary.json");
  const nlohmann::json json = nlohmann::json::parse(in);
  CHECK(json.at("mean_abs_steer_step").get<double>() == Approx(summary.mean_abs_steer_step));
  CHECK(json.at("mean_abs_throttle_step").get<double>() == Approx(summary.mean_abs_throttle_step));
  std::filesystem::remove_all(config.out_dir);
}
