// The four-wheel physics models in the closed loop: MPPI with the full-vehicle model laps the
// Gazebo oval on the full-vehicle plant, and the double-track plant under the single-track
// model; unknown names list the new ones.
#include <catch2/catch.hpp>

#include <string>

#include "error_of.hpp"
#include "sim/closed_loop.hpp"

namespace {
mppi::sim::ClosedLoopConfig physics_run(const std::string& model, const std::string& plant) {
  mppi::sim::ClosedLoopConfig c;
  c.track = "gazebo";
  c.model = model;
  c.plant = plant;
  c.target_speed_mps = 5.0;
  c.laps = 1;
  c.controller.num_samples = 384;
  c.controller.horizon = 60;
  c.controller.seed = 3;
  c.progress = false;
  return c;
}
}  // namespace

TEST_CASE("full-vehicle MPPI laps the oval on the full-vehicle plant", "[sim][closed_loop][full_vehicle]") {
  const auto summary = mppi::sim::run_closed_loop(physics_run("full-vehicle", "full-vehicle"));
  CHECK(summary.laps_completed == 1);
  CHECK(summary.crashes == 0);
  REQUIRE(summary.lap_times_s.size() == 1);
  // ~61.6 m centreline at 3-6 m/s with a standing start: 10-21 s.
  CHECK(summary.lap_times_s[0] > 10.0);
  CHECK(summary.lap_times_s[0] < 21.0);
}

TEST_CASE("single-track MPPI laps the oval on the double-track plant", "[sim][closed_loop][double_track]") {
  const auto summary = mppi::sim::run_closed_loop(physics_run("single-track", "double-track"));
  CHECK(summary.laps_completed == 1);
  CHECK(summary.crashes == 0);
  CHECK(summary.mean_speed_mps > 3.0);
}

TEST_CASE("closed loop names the four-wheel models when a name is unknown", "[sim][closed_loop]") {
  using mppi::test::error_of;
  CHECK_THAT(error_of([] { mppi::sim::run_closed_loop(physics_run("double-trak", "single-track")); }),
             Catch::Contains("double-track") && Catch::Contains("full-vehicle"));
  CHECK_THAT(error_of([] { mppi::sim::run_closed_loop(physics_run("single-track", "full-vehicel")); }),
             Catch::Contains("full-vehicle") && Catch::Contains("double-track"));
}
