// The synthetic recordings' driver: a target-speed schedule (as a human on a track: speed up,
// cruise, brake) that the closed loop follows. Oracles: the schedule's stated ranges, and the
// plant's measured speed against the target it was given.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "base/error.hpp"
#include "diagnose/synth.hpp"
#include "sim/closed_loop.hpp"
#include "sim/recording.hpp"

using namespace mppi;

TEST_CASE("speed schedule: speeds and hold times stay in their ranges and cover the run", "[diagnose]") {
  const auto s = diagnose::speed_schedule(7, 60.0, 3.0, 8.0, 2.0, 6.0);
  REQUIRE(s.size() >= 10);  // 60 s in holds of at most 6 s
  CHECK(s.front().first == 0.0);
  CHECK(s.back().first < 60.0);
  CHECK(60.0 - s.back().first <= 6.0);
  double lo = 1e9, hi = -1e9;
  for (std::size_t i = 0; i < s.size(); ++i) {
    CHECK(s[i].second >= 3.0);
    CHECK(s[i].second <= 8.0);
    lo = std::min(lo, s[i].second);
    hi = std::max(hi, s[i].second);
    if (i > 0) {
      CHECK(s[i].first - s[i - 1].first >= 2.0);
      CHECK(s[i].first - s[i - 1].first <= 6.0);
    }
  }
  CHECK(hi - lo > 2.5);  // it really varies
  CHECK(diagnose::speed_schedule(7, 60.0, 3.0, 8.0, 2.0, 6.0) == s);
  CHECK(diagnose::speed_schedule(8, 60.0, 3.0, 8.0, 2.0, 6.0) != s);
  CHECK_THROWS_AS(diagnose::speed_schedule(1, 60.0, 5.0, 3.0, 2.0, 6.0), Error);
  CHECK_THROWS_AS(diagnose::speed_schedule(1, 60.0, 3.0, 8.0, 0.0, 6.0), Error);
}

TEST_CASE("closed loop follows a target-speed schedule (slow, then fast, then braking)", "[diagnose]") {
  const std::string dir = (std::filesystem::temp_directory_path() / "mppi_test_speed_schedule").string();
  sim::ClosedLoopConfig c;
  c.model = c.plant = "single-track";
  c.laps = 100;
  c.max_time_s = 13.0;
  c.controller.num_samples = 64;
  c.controller.horizon = 30;
  c.controller.seed = 3;
  c.target_speed_schedule = {{0.0, 2.5}, {4.0, 6.5}, {8.0, 2.5}};
  c.out_dir = dir;
  c.progress = false;
  sim::run_closed_loop(c);
  const sim::Recording rec = sim::RecordingReader::read(dir + "/log.csv");
  const auto& t = rec.column("t");
  const auto& vx = rec.column("vx");
  const auto& th = rec.column("throttle");
  auto mean_in = [&](const std::vector<double>& col, double a, double b) {
    double sum = 0;
    int n = 0;
    for (std::size_t k = 0; k < rec.rows(); ++k)
      if (t[k] >= a && t[k] < b) sum += col[k], ++n;
    return n ? sum / n : NAN;
  };
  const double slow = mean_in(vx, 2.0, 4.0), fast = mean_in(vx, 6.5, 8.0), slow_again = mean_in(vx, 10.5, 13.0);
  INFO("mean v_x: " << slow << " / " << fast << " / " << slow_again << " m/s");
  CHECK(std::abs(slow - 2.5) < 0.6);
  CHECK(fast > slow + 1.5);
  CHECK(std::abs(slow_again - 2.5) < 0.6);
  // Braking at the step down: a clearly negative throttle right after t = 8 s.
  double min_throttle = 1.0;
  for (std::size_t k = 0; k < rec.rows(); ++k)
    if (t[k] >= 8.0 && t[k] < 10.0) min_throttle = std::min(min_throttle, th[k]);
  CHECK(min_throttle < -0.1);
  std::filesystem::remove_all(dir);
}
