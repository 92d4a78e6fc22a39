// Calibration: pulse widths stay within [min, max], a command means the same on every
// calibrated chassis, the pulse -> value inverse is exact; AutoRally's YAML formats load and
// bad files name file:line:column.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

#include "chassis/calibration.hpp"
#include "chassis/priorities.hpp"
#include "error_of.hpp"

using namespace mppi::chassis;
using mppi::test::error_of;

TEST_CASE("pulse widths never leave [min, max] and mean the same on every chassis",
          "[chassis][calibration]") {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> us(500, 2500);
  long inexact = 0, total = 0;
  for (int k = 0; k < 2000; ++k) {
    ActuatorCalibration a;
    int p[3] = {us(rng), us(rng), us(rng)};
    std::sort(p, p + 3);
    if (p[0] == p[1] || p[1] == p[2]) continue;
    a.min_us = p[0], a.center_us = p[1], a.max_us = p[2];
    a.reverse = k % 2;
    REQUIRE(a.is_valid(nullptr));
    CHECK(a.pulse_us(0.0) == a.center_us);
    CHECK(a.pulse_us(a.reverse ? -1.0 : 1.0) == a.max_us);
    CHECK(a.pulse_us(a.reverse ? 1.0 : -1.0) == a.min_us);
    double prev = a.reverse ? a.max_us : a.min_us;
    for (int i = 0; i <= 200; ++i) {
      const float v = -1.f + 0.01f * static_cast<float>(i);
      const double pw = a.pulse_us(v);
      REQUIRE(pw >= a.min_us);
      REQUIRE(pw <= a.max_us);
      // Monotone in the command (decreasing when reversed).
      REQUIRE((a.reverse ? pw <= prev : pw >= prev));
      prev = pw;
      // Same behaviour on any chassis: the normalised deflection equals the command.
      const double s = a.reverse ? -v : v;
      const double deflection = s >= 0 ? (pw - a.center_us) / (a.max_us - a.center_us)
                                       : (pw - a.center_us) / (a.center_us - a.min_us);
      REQUIRE(deflection == Approx(s).margin(1e-12));
      // The inverse gives back the float command exactly.
      ++total;
      inexact += static_cast<float>(a.value(pw)) != v;
    }
    // Garbage in (never produced by a validated command) still gives a pulse inside the range.
    for (double bad : {std::numeric_limits<double>::quiet_NaN(), 7.0, -1e9,
                       std::numeric_limits<double>::infinity()}) {
      CHECK(a.pulse_us(bad) >= a.min_us);
      CHECK(a.pulse_us(bad) <= a.max_us);
    }
  }
  CHECK(total > 100000);
  CHECK(inexact == 0);
}

TEST_CASE("AutoRally's calibration files load, bad ones are named", "[chassis][calibration]") {
  const auto by_name = Calibration::parse_yaml(
      "steering: {center: 1520, min: 1050, max: 1990, reverse: true}\n"
      "throttle: {center: 1500, min: 1000, max: 2000, reverse: false}\n"
      "frontBrake: {center: 1500, min: 1500, max: 1900, reverse: false}\n",
      "a.yaml");
  CHECK(by_name.steering.center_us == 1520);
  CHECK(by_name.steering.reverse);
  CHECK(by_name.front_brake.max_us == 1900);
  // Full left (+1 here, ISO) on a reversed servo is the minimum pulse.
  CHECK(by_name.pulses({1.f, 0.f, 1.f}).steering_us == 1050);
  CHECK(by_name.pulses({1.f, 0.f, 1.f}).front_brake_us == 1900);
  const auto by_index = Calibration::parse_yaml(
      "'0': {name: 'steering', center: 1500, min: 1000, max: 2000, reverse: false}\n"
      "'1': {name: 'throttle', center: 1500, min: 1000, max: 2000, reverse: false}\n"
      "'2': {name: 'frontBrake', center: 1500, min: 1500, max: 2000, reverse: false}\n",
      "b.yaml");
  CHECK(by_index.throttle.min_us == 1000);
  CHECK(by_index.neutral().front_brake_us == 1500);

  const std::string good_rest =
      "throttle: {center: 1500, min: 1000, max: 2000, reverse: false}\n"
      "frontBrake: {center: 1500, min: 1500, max: 2000, reverse: false}\n";
  CHECK_THAT(error_of([&] {
               Calibration::parse_yaml("steering: {center: 1500, min: 1600, max: 2000, reverse: false}\n" +
                                           good_rest, "c.yaml");
             }),
             Catch::Contains("c.yaml:1:11") && Catch::Contains("min <= center <= max"));
  CHECK_THAT(error_of([&] {
               Calibration::parse_yaml("steering: {center: 1500, min: 1000, max: 2000, reverse: false, trim: 3}\n" +
                                           good_rest, "d.yaml");
             }),
             Catch::Contains("d.yaml:1") && Catch::Contains("unknown key 'trim'"));
  CHECK_THAT(error_of([&] { Calibration::parse_yaml(good_rest, "e.yaml"); }),
             Catch::Contains("missing actuator 'steering'"));
  CHECK_THAT(error_of([&] {
               Calibration::parse_yaml("steering: {center: 1500, min: 1000, max: nan, reverse: false}\n" +
                                           good_rest, "f.yaml");
             }),
             Catch::Contains("f.yaml:1:42") && Catch::Contains("'max'"));
  CHECK_THAT(error_of([&] {
               Calibration::parse_yaml("steering: {center: 1500, min: 1000, max: 2000, reverse: 2}\n" +
                                           good_rest, "g.yaml");
             }),
             Catch::Contains("'reverse' must be true or false"));
}

TEST_CASE("AutoRally's priority file loads best first, ties and junk are rejected",
          "[chassis][priorities]") {
  const auto p = Priorities::parse_yaml(
      "'imlearn': 0\n'mppi_controller': 1\n'constantSpeedController': 2\n'waypointFollower': 3\n"
      "'joystick': 4\n'OCS': 5\n'RC': 7\n",
      "p.yaml");
  REQUIRE(p.size() == 7);
  CHECK(p.entries()[0].sender == "imlearn");
  CHECK(p.entries()[6].sender == "RC");
  CHECK(p.index_of("joystick") == 4);
  CHECK(p.index_of("nobody") == -1);
  const auto nested = Priorities::parse_yaml(
      "chassisCommandPriorities:\n  joystick: 9\n  mppi: 2\n", "n.yaml");
  CHECK(nested.entries()[0].sender == "mppi");
  CHECK_THAT(error_of([] { Priorities::parse_yaml("a: 1\nb: 1\n", "t.yaml"); }),
             Catch::Contains("t.yaml:2:4") && Catch::Contains("already taken"));
  CHECK_THAT(error_of([] { Priorities::parse_yaml("a: 1.5\n", "u.yaml"); }),
             Catch::Contains("u.yaml:1:4") && Catch::Contains("integer"));
  CHECK_THAT(error_of([] { Priorities::parse_yaml("a: -1\n", "v.yaml"); }),
             Catch::Contains("v.yaml:1:4"));
}

TEST_CASE("the shipped chassis configuration files load", "[chassis][calibration]") {
  const std::string dir = MPPI_TEST_DATA_DIR;
  const auto cal = Calibration::load_yaml(dir + "/config/chassis_calibration.yaml");
  CHECK(cal.steering.center_us == 1500);
  CHECK(cal.front_brake.min_us == 1500);
  const auto p = Priorities::load_yaml(dir + "/config/chassis_priorities.yaml");
  CHECK(p.entries().front().sender == "mppi");
  for (const auto& e : p.entries()) CHECK(e.sender.size() <= 15);  // fits the UDP sender field
}
