// Short closed-loop runs in the simulator: MPPI must lap the Gazebo oval without touching a
// barrier, near the target speed, and a run must be reproducible from its seed.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "sim/closed_loop.hpp"
#include "sim/recording.hpp"

namespace {
mppi::sim::ClosedLoopConfig short_run(const std::string& model) {
  mppi::sim::ClosedLoopConfig c;
  c.track = "gazebo";
  c.model = model;
  c.plant = "single-track";
  c.target_speed_mps = 5.0;
  c.laps = 1;
  c.controller.num_samples = 384;
  c.controller.horizon = 60;
  c.controller.seed = 3;
  c.progress = false;
  return c;
}
}  // namespace

TEST_CASE("single-track MPPI laps the Gazebo oval without crashing", "[sim][closed_loop]") {
  const auto summary = mppi::sim::run_closed_loop(short_run("single-track"));
  CHECK(summary.laps_completed == 1);
  CHECK(summary.crashes == 0);
  REQUIRE(summary.lap_times_s.size() == 1);
  // The centreline is ~61.6 m: a lap at 3-6 m/s takes 10-21 s (standing start included).
  CHECK(summary.lap_times_s[0] > 10.0);
  CHECK(summary.lap_times_s[0] < 21.0);
  CHECK(summary.max_speed_mps < 5.0 * 1.4);
  // Lap 1 starts from rest at the start line: it is measured against the standing-start limit lap,
  // which is slower than the flying one and no faster than the lap itself.
  REQUIRE(summary.lap_time_ratio.size() == 1);
  CHECK(summary.standing_limit_lap_s > summary.limit_lap_s);
  CHECK(summary.lap_time_ratio[0] == Approx(summary.lap_times_s[0] / summary.standing_limit_lap_s).epsilon(1e-12));
  CHECK(summary.lap_time_ratio[0] >= 1.0);
}

TEST_CASE("the AutoRally network drives the physics plant around the oval", "[sim][closed_loop]") {
  auto config = short_run("autorally-nn");
  const std::string out = (std::filesystem::temp_directory_path() /
                           ("mppi_closed_loop_nn_" + std::to_string(::getpid()))).string();
  config.out_dir = out;
  const auto summary = mppi::sim::run_closed_loop(config);
  CHECK(summary.laps_completed == 1);
  CHECK(summary.crashes == 0);
  CHECK(summary.mean_speed_mps > 3.0);
  // The run's outputs exist and the log is a valid recording whose duration is the run's.
  const auto log = mppi::sim::RecordingReader::read(out + "/log.csv");
  REQUIRE(log.rows() > 100);
  CHECK(log.column("t").back() == Approx(summary.sim_time_s).margin(0.03));
  CHECK(std::filesystem::file_size(out + "/track.png") > 10000);
  std::ifstream json(out + "/summary.json");
  std::string text((std::istreambuf_iterator<char>(json)), {});
  CHECK(text.find("\"laps_completed\": 1") != std::string::npos);
  CHECK(std::filesystem::file_size(out + "/track_slip.png") > 10000);
  // Body slip and lateral acceleration in the log, recomputed from the logged velocities:
  // slip = atan2(vy, vx); a_y = dvy/dt + vx r (backward difference over the control step).
  const auto& t = log.column("t");
  const auto& vx = log.column("vx");
  const auto& vy = log.column("vy");
  const auto& r = log.column("yaw_rate");
  const auto& slip = log.column("slip_angle_rad");
  const auto& ay = log.column("lateral_accel_mps2");
  double peak_slip = 0, peak_ay = 0;
  for (std::size_t i = 1; i < log.rows(); ++i) {
    CHECK(slip[i] == Approx(std::atan2(vy[i], vx[i])).margin(1e-5));
    CHECK(ay[i] == Approx((vy[i] - vy[i - 1]) / (t[i] - t[i - 1]) + vx[i] * r[i]).margin(1e-3));
    if (vx[i] > 1.0) {
      peak_slip = std::max(peak_slip, std::abs(slip[i]));
      peak_ay = std::max(peak_ay, std::abs(ay[i]));
    }
  }
  CHECK(summary.peak_slip_angle_rad == Approx(peak_slip).margin(1e-5));
  CHECK(summary.peak_lateral_accel_mps2 == Approx(peak_ay).margin(1e-3));
  CHECK(summary.p95_slip_angle_rad <= summary.peak_slip_angle_rad);
}

TEST_CASE("a closed-loop run is reproducible from its seed", "[sim][closed_loop]") {
  auto config = short_run("kinematic");
  config.max_time_s = 4.0;
  config.laps = 5;
  const auto a = mppi::sim::run_closed_loop(config);
  config.controller.num_threads = 1;
  const auto b = mppi::sim::run_closed_loop(config);
  CHECK(a.mean_speed_mps == b.mean_speed_mps);
  CHECK(a.max_speed_mps == b.max_speed_mps);
  config.controller.seed = 4;
  const auto c = mppi::sim::run_closed_loop(config);
  CHECK(c.mean_speed_mps != a.mean_speed_mps);
}

TEST_CASE("bad closed-loop settings are rejected clearly", "[sim][closed_loop]") {
  auto config = short_run("no-such-model");
  CHECK_THROWS_WITH(mppi::sim::run_closed_loop(config), Catch::Contains("no-such-model"));
  config = short_run("kinematic");
  config.track = "monza";
  CHECK_THROWS_WITH(mppi::sim::run_closed_loop(config), Catch::Contains("gazebo"));
  // the controller's own cost map is read from the file given, and a missing one is named
  config = short_run("kinematic");
  config.cost_map_npz = "no_such_dir/racing_line_costmap.npz";
  CHECK_THROWS_WITH(mppi::sim::run_closed_loop(config), Catch::Contains("racing_line_costmap.npz"));
}

namespace {
// Pulls the operator's runstop before the first step and leaves it pulled.
class RunstopHeld : public mppi::sim::StepObserver {
 public:
  void on_start(mppi::sim::PathPredictor) override {}
  void after_step(const mppi::sim::StepView&) override {}
  mppi::sim::OperatorRequests poll_requests(double) override {
    mppi::sim::OperatorRequests r;
    r.motion_enabled = false;
    return r;
  }
};
}  // namespace

TEST_CASE("a car that cannot move is found stalled and put back, and is not counted as a crash",
          "[sim][closed_loop]") {
  // No drive at all (throttle held at or below 0): the car stays where it starts, so it makes
  // no progress and the stall watch (10 s, 2 m) must fire at t = 10 s and again at 20 s.
  auto config = short_run("single-track");
  config.actuators.throttle_max = 0.f;
  config.max_time_s = 25.0;
  const auto summary = mppi::sim::run_closed_loop(config);
  CHECK(summary.laps_completed == 0);
  CHECK_FALSE(summary.finished);
  CHECK(summary.crashes == 0);
  REQUIRE(summary.stalls == 2);
  REQUIRE(summary.stall_times_s.size() == 2);
  CHECK(summary.stall_times_s[0] == Approx(10.0).margin(0.03));
  CHECK(summary.stall_times_s[1] == Approx(20.0).margin(0.05));
  CHECK(mppi::sim::to_json(summary).find("\"stalls\": 2") != std::string::npos);

  // Off: no stall is counted.
  config.stall_timeout_s = 0.0;
  CHECK(mppi::sim::run_closed_loop(config).stalls == 0);
}

TEST_CASE("a car held by the operator's runstop is not stalled", "[sim][closed_loop]") {
  auto config = short_run("single-track");
  config.max_time_s = 15.0;
  RunstopHeld runstop;
  config.observer = &runstop;
  const auto summary = mppi::sim::run_closed_loop(config);
  CHECK(summary.max_speed_mps < 0.1);  // the runstop held it
  CHECK(summary.stalls == 0);
  CHECK(summary.crashes == 0);
}

TEST_CASE("a lap at speed is no stall", "[sim][closed_loop]") {
  auto config = short_run("single-track");
  config.stall_timeout_s = 3.0;  // a lap of ~15 s makes 2 m in far less than 3 s once rolling
  const auto summary = mppi::sim::run_closed_loop(config);
  CHECK(summary.laps_completed == 1);
  CHECK(summary.stalls == 0);
}
