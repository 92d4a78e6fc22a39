// Lap counting on a synthetic ring track, against the closed form lap time 2 pi r / v.
#include <catch2/catch.hpp>

#include <cmath>

#include "sim/lap_counter.hpp"
#include "sim/track.hpp"

using namespace mppi::sim;

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kR = 10.0;  // centreline radius [m]

Polyline ring(double r, int n) {
  Polyline p;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n;
    p.push_back({r * std::cos(a), r * std::sin(a)});
  }
  return p;
}
const Track& ring_track() {
  static const Track t = Track::from_boundaries("ring", ring(kR - 1.0, 600), ring(kR + 1.0, 600), {}, "", {});
  return t;
}
Vec2 on_circle(double angle) { return {kR * std::cos(angle), kR * std::sin(angle)}; }
double start_angle() {
  const Pose2 s = ring_track().start_pose();
  return std::atan2(s.y_m, s.x_m);
}
}  // namespace

TEST_CASE("lap counter: constant speed on a circle gives laps of 2 pi r / v", "[sim]") {
  const double v = 5.0, dt = 0.01;
  const double lap_s = 2.0 * kPi * kR / v;  // 12.566 s
  LapCounter laps(ring_track());
  const double a0 = start_angle();
  const int steps = static_cast<int>(3.5 * lap_s / dt);
  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    laps.update(on_circle(a0 + v * t / kR), t);  // CCW = the driving direction
  }
  REQUIRE(laps.laps_completed() == 3);
  for (double lt : laps.lap_times_s()) CHECK(lt == Approx(lap_s).margin(2e-3));
  CHECK(laps.progress_m() / laps.length_m() == Approx(3.5).margin(1e-3));
  CHECK(laps.lateral_error_m() < 0.02);
  CHECK(laps.rejected_jumps() == 0);
}

TEST_CASE("lap counter: driving backwards reduces progress and counts no lap", "[sim]") {
  LapCounter laps(ring_track());
  const double a0 = start_angle();
  for (int k = 0; k <= 2000; ++k) laps.update(on_circle(a0 - 2.0 * 2.0 * kPi * k / 2000.0), 0.01 * k);
  CHECK(laps.laps_completed() == 0);
  CHECK(laps.progress_m() == Approx(-2.0 * laps.length_m()).margin(0.05));
}

TEST_CASE("lap counter: crossing the line back and forth counts the lap once", "[sim]") {
  LapCounter laps(ring_track());
  const double a0 = start_angle();
  double t = 0.0;
  const auto drive = [&](double from_laps, double to_laps) {
    const int n = 1000;
    for (int k = 1; k <= n; ++k) {
      t += 0.01;
      laps.update(on_circle(a0 + 2.0 * kPi * (from_laps + (to_laps - from_laps) * k / n)), t);
    }
  };
  laps.update(on_circle(a0), 0.0);
  drive(0.0, 1.02);  // over the line: lap 1
  drive(1.02, 0.95); // back over it
  drive(0.95, 1.5);  // forward again: still lap 1
  CHECK(laps.laps_completed() == 1);
  CHECK(laps.lap_times_s().size() == 1);
  // The line was first crossed at 1/1.02 of the first 10 s leg.
  CHECK(laps.lap_times_s()[0] == Approx(10.0 / 1.02).margin(0.02));
}

TEST_CASE("lap counter: cutting across the infield does not count as progress", "[sim]") {
  LapCounter laps(ring_track());
  const double a0 = start_angle();
  double t = 0.0;
  laps.update(on_circle(a0), t);
  // Straight across the infield along the diameter to the opposite side, 5 cm per update.
  const Vec2 from = on_circle(a0), to = on_circle(a0 + kPi);
  for (int k = 1; k <= 400; ++k) {
    t += 0.01;
    laps.update(from + (k / 400.0) * (to - from), t);
  }
  CHECK(laps.rejected_jumps() >= 1);
  CHECK(std::abs(laps.progress_m()) < 1.0);
  // Then half a lap forward along the track: that counts, but makes no full lap.
  for (int k = 1; k <= 500; ++k) {
    t += 0.01;
    laps.update(on_circle(a0 + kPi + kPi * k / 500.0), t);
  }
  CHECK(laps.laps_completed() == 0);
  CHECK(laps.progress_m() == Approx(0.5 * laps.length_m()).margin(1.0));
}

TEST_CASE("lap counter: a teleport far along the track is rejected", "[sim]") {
  LapCounter laps(ring_track());
  const double a0 = start_angle();
  laps.update(on_circle(a0), 0.0);
  laps.update(on_circle(a0 + 0.01), 0.01);
  const double before = laps.progress_m();
  CHECK(before == Approx(0.01 * laps.length_m() / (2.0 * kPi)).margin(0.01));
  laps.update(on_circle(a0 + 2.0), 0.02);  // 20 m in one update
  CHECK(laps.rejected_jumps() == 1);
  CHECK(laps.progress_m() == before);
  laps.update(on_circle(a0 + 2.05), 0.03);  // continues from the new place
  CHECK(laps.progress_m() == Approx(before + 0.05 * kR).margin(0.02));
}
