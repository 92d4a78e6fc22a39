// Nice ticks: closed-form cases worked by hand, and the defining properties (step 1/2/5 x 10^k,
// limits on multiples of the step covering the data, at most N intervals, no smaller nice step
// would do) over many random ranges.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

#include "plot/ticks.hpp"

using namespace mppi::plot;

namespace {
bool is_nice(double step) {
  const double k = std::floor(std::log10(step) + 1e-9);
  const double m = step / std::pow(10.0, k);
  return std::abs(m - 1) < 1e-9 || std::abs(m - 2) < 1e-9 || std::abs(m - 5) < 1e-9;
}
double next_smaller_nice(double step) {
  const double k = std::floor(std::log10(step) + 1e-9);
  const long m = std::lround(step / std::pow(10.0, k));
  return m == 1 ? 0.5 * std::pow(10.0, k) : m == 2 ? std::pow(10.0, k) : 2 * std::pow(10.0, k);
}
}  // namespace

TEST_CASE("nice axis: hand-worked cases", "[plot]") {
  // The steering axis that once read "0 ... 1 ... 0.585": steps 0.1 from 0 to 0.6.
  NiceAxis a = nice_axis(0.0, 0.585, 6);
  CHECK(a.step == Approx(0.1));
  CHECK(a.lo == 0.0);
  CHECK(a.hi == Approx(0.6));
  REQUIRE(a.ticks.size() == 7);
  CHECK(a.ticks[3] == Approx(0.3));
  // [-3.2, 17] in at most 6 steps: step 2 needs [-4, 18] = 11 steps, step 5 gives [-5, 20].
  a = nice_axis(-3.2, 17.0, 6);
  CHECK(a.step == Approx(5.0));
  CHECK(a.lo == Approx(-5.0));
  CHECK(a.hi == Approx(20.0));
  // A narrow range far from zero.
  a = nice_axis(1234.0, 1236.5, 5);
  CHECK(a.step == Approx(0.5));
  CHECK(a.lo == Approx(1234.0));
  CHECK(a.hi == Approx(1236.5));
  // A single value is widened by 10 %: [9, 11].
  a = nice_axis(10.0, 10.0, 4);
  CHECK(a.lo <= 9.0);
  CHECK(a.hi >= 11.0);
  // Ticks inside fixed limits.
  // Ticks inside fixed limits: step 0.1 gives 13 ticks, 0.2 gives -0.2 ... 0.8 (6 <= 7).
  a = ticks_inside(-0.37, 0.91, 6);
  CHECK(a.step == Approx(0.2));
  REQUIRE(a.ticks.size() == 6);
  CHECK(a.ticks.front() == Approx(-0.2));
  CHECK(a.ticks.back() == Approx(0.8));
}

TEST_CASE("nice axis: properties over random ranges", "[plot]") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> exp10(-6, 6), unit(-1, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    const double scale = std::pow(10.0, exp10(rng));
    const double a0 = unit(rng) * scale, a1 = a0 + std::abs(unit(rng)) * scale * 0.7 + 1e-9 * scale;
    const int n = 2 + trial % 9;
    const NiceAxis a = nice_axis(a0, a1, n);
    INFO("range [" << a0 << ", " << a1 << "], n " << n << ": step " << a.step << " [" << a.lo << ", " << a.hi << "]");
    REQUIRE(is_nice(a.step));
    CHECK(a.lo <= a0 + 1e-9 * scale);
    CHECK(a.hi >= a1 - 1e-9 * scale);
    CHECK(std::abs(a.lo / a.step - std::round(a.lo / a.step)) < 1e-6);
    CHECK(std::abs(a.hi / a.step - std::round(a.hi / a.step)) < 1e-6);
    const long intervals = std::lround((a.hi - a.lo) / a.step);
    CHECK(intervals <= n);
    CHECK(a.ticks.size() == static_cast<std::size_t>(intervals + 1));
    // Minimal: the next smaller nice step needs more than n intervals.
    const double s = next_smaller_nice(a.step);
    CHECK(std::ceil(a1 / s - 1e-9) - std::floor(a0 / s + 1e-9) > n);
  }
}

TEST_CASE("tick labels carry the decimals the step needs", "[plot]") {
  CHECK(tick_label(0.30000000000000004, 0.1) == "0.3");
  CHECK(tick_label(-1e-17, 0.1) == "0.0");  // never "-0.0"
  CHECK(tick_label(1234.5, 0.5) == "1234.5");
  CHECK(tick_label(20.0, 5.0) == "20");
  CHECK(tick_label(0.025, 0.005) == "0.025");
  CHECK(tick_label(3e7, 1e7) == "3.0e+07");
}

TEST_CASE("nice axis: non-finite ranges are refused by name", "[plot]") {
  CHECK_THROWS_WITH(nice_axis(std::numeric_limits<double>::quiet_NaN(), 1.0), Catch::Contains("not finite"));
  CHECK_THROWS_WITH(ticks_inside(1.0, 1.0), Catch::Contains("empty range"));
}
