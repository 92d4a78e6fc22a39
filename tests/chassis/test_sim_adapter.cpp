// The simulator behind the chassis interface: the plant sees exactly what the controller sent
// (the calibration round trip is exact down to 2^-26), the runstop and watchdog act on the simulated car, and
// a closed-loop run through the adapter gives the same laps as the direct path.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "chassis/sim_adapter.hpp"
#include "sim/closed_loop.hpp"
#include "test_data.hpp"

using namespace mppi::chassis;

TEST_CASE("the sim adapter passes valid commands through bit-exactly", "[chassis][sim]") {
  SimChassis sim;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  long differ = 0;
  double t = 0.0;
  for (int i = 0; i < 200000; ++i, t += 0.02) {
    mppi::Control c{u(rng), u(rng)};
    if (i % 7 == 0) c.steer = std::ldexp(c.steer, -std::uniform_int_distribution<int>(1, 60)(rng));
    const mppi::Control out = sim.drive(c, t);
    // Exact for |v| >= 2^-26; below, 1500 + 500 v rounds in double and the value comes back
    // within 1e-15 (a femtosecond of pulse width).
    for (auto [sent, got] : {std::pair{c.steer, out.steer}, std::pair{c.throttle, out.throttle}}) {
      if (std::abs(sent) >= std::ldexp(1.f, -26))
        differ += std::memcmp(&sent, &got, sizeof(float)) != 0;
      else
        REQUIRE(std::abs(sent - got) <= 1e-15);
    }
    REQUIRE(sim.last_output().pulses.steering_us >= 1000.0);
    REQUIRE(sim.last_output().pulses.steering_us <= 2000.0);
  }
  CHECK(differ == 0);
}

TEST_CASE("the simulated car obeys runstop and watchdog", "[chassis][sim]") {
  SimChassis sim;
  CHECK(sim.drive({0.4f, 0.7f}, 0.0).throttle == 0.7f);
  // A NaN output is rejected: the previous command holds while fresh, then the watchdog.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  CHECK(sim.drive({nan, nan}, 0.05).throttle == 0.7f);
  const auto held = sim.drive({nan, 0.1f}, 0.12);
  CHECK(held.throttle == 0.f);
  CHECK(held.steer == 0.f);
  CHECK(sim.last_output().decision.watchdog_tripped);
  CHECK(sim.arbiter().counters().invalid[static_cast<int>(CommandError::kSteeringNotFinite)] == 2);
  sim.set_motion_enabled(false);
  const auto stopped = sim.drive({0.4f, 0.7f}, 0.2);
  CHECK(stopped.throttle == 0.f);
  CHECK(stopped.steer == 0.4f);
}

TEST_CASE("a closed-loop run through the chassis adapter laps exactly like the direct path",
          "[chassis][sim][closed_loop]") {
  mppi::sim::ClosedLoopConfig c;
  c.track = "gazebo";
  // The single-track controller on the (calibrated) single-track plant laps without a crash
  // for every seed tried (1, 2, 3, 7 at 5 m/s), so a run that changes by rounding (the TSan
  // build has no AVX-512 clones) still completes its lap.
  c.model = "single-track";
  c.plant = "single-track";
  c.target_speed_mps = 5.0;
  c.laps = 1;
  c.controller.num_samples = 256;
  c.controller.horizon = 50;
  c.controller.seed = 7;
  c.progress = false;
  c.through_chassis = true;
  const auto adapter = mppi::sim::run_closed_loop(c);
  c.through_chassis = false;
  const auto direct = mppi::sim::run_closed_loop(c);
  INFO("adapter: laps " << adapter.laps_completed << " crashes " << adapter.crashes << " t " << adapter.sim_time_s << " direct laps " << direct.laps_completed << " crashes " << direct.crashes);
  REQUIRE(adapter.laps_completed == 1);
  CHECK(adapter.crashes == 0);
  CHECK(adapter.lap_times_s == direct.lap_times_s);
  CHECK(adapter.crashes == direct.crashes);
  CHECK(adapter.sim_time_s == direct.sim_time_s);
  CHECK(adapter.max_speed_mps == direct.max_speed_mps);
  CHECK(adapter.mean_speed_mps == direct.mean_speed_mps);
}
