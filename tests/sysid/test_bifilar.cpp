// Bifilar pendulum: the formula against a numerically integrated pendulum (exact wire
// geometry), the general form's reductions, and the AutoRally paper's MOI table: which rows
// the printed T, b, d and masses reproduce within the precision they were printed to.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <string>

#include "error_of.hpp"
#include "sysid/bifilar.hpp"

using namespace mppi::sysid;

namespace {

// Period of a body (inertia I, mass m) on two parallel wires of length d, b from its axis,
// from the exact potential V = m g (d - sqrt(d^2 - 4 b^2 sin^2(theta / 2))), integrated
// (RK4) from a small twist; time between the first and the 21st downward zero crossing / 20.
double simulated_period(double I, double m, double b, double d, double g, double amplitude) {
  auto accel = [&](double th) {
    const double s = std::sin(th / 2), c = std::cos(th / 2);
    const double root = std::sqrt(d * d - 4 * b * b * s * s);
    return -m * g * (2 * b * b * s * c / root) / I;  // -dV/dtheta / I
  };
  double th = amplitude, w = 0, t = 0, first = -1, last = -1;
  const double h = 1e-4;
  int crossings = 0;
  while (crossings < 21) {
    const double k1t = w, k1w = accel(th);
    const double k2t = w + h / 2 * k1w, k2w = accel(th + h / 2 * k1t);
    const double k3t = w + h / 2 * k2w, k3w = accel(th + h / 2 * k2t);
    const double k4t = w + h * k3w, k4w = accel(th + h * k3t);
    const double th_new = th + h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
    w += h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w);
    if (th > 0 && th_new <= 0) {
      const double tc = t + h * th / (th - th_new);
      if (crossings == 0) first = tc;
      last = tc;
      ++crossings;
    }
    th = th_new;
    t += h;
  }
  return (last - first) / 20;
}

}  // namespace

TEST_CASE("Bifilar formula matches a simulated two-wire pendulum", "[sysid][bifilar]") {
  for (const auto& [I, m, b, d] : {std::array<double, 4>{1.124, 21.88, 0.26, 1.93},
                                   std::array<double, 4>{0.048, 1.64, 0.182, 0.935},
                                   std::array<double, 4>{0.35, 21.88, 0.14, 1.9}}) {
    const double T = simulated_period(I, m, b, d, 9.81, 0.01);
    CHECK(bifilar_inertia_parallel(m, T, b, d) == Approx(I).epsilon(2e-4));
  }
}

TEST_CASE("Bifilar general form: reductions, inverse, errors", "[sysid][bifilar]") {
  const double pi = std::numbers::pi;
  CHECK(bifilar_inertia(10.0, 2.0, 0.3, 0.3, 1.5) == Approx(10 * 9.81 * 0.09 * 4 / (4 * pi * pi * 1.5)));
  CHECK(bifilar_inertia_parallel(10.0, 2.0, 0.3, 1.5) == bifilar_inertia(10.0, 2.0, 0.3, 0.3, 1.5));
  // Asymmetric wires: torque m g R1 R2 theta / h (tensions m g R2 / (R1+R2), m g R1 / (R1+R2)).
  CHECK(bifilar_inertia(10.0, 2.0, 0.4, 0.2, 1.5) == Approx(bifilar_inertia_parallel(10.0, 2.0, std::sqrt(0.08), 1.5)));
  CHECK(bifilar_height(1.9, 0.2, 0.2) == 1.9);
  CHECK(bifilar_height(1.0, 0.9, 0.3) == Approx(0.8));
  CHECK(bifilar_period(bifilar_inertia(3.0, 1.7, 0.2, 0.25, 1.1), 3.0, 0.2, 0.25, 1.1) == Approx(1.7));
  using mppi::test::error_of;
  CHECK_THAT(error_of([] { bifilar_inertia_parallel(-1.0, 2.0, 0.3, 1.5); }), Catch::Contains("mass"));
  CHECK_THAT(error_of([] { bifilar_height(0.5, 0.9, 0.3); }), Catch::Contains("R1 - R2"));
}

TEST_CASE("AutoRally bifilar table: reproduced within printing precision except I_x",
          "[sysid][bifilar]") {
  const auto table = autorally_bifilar_table();
  REQUIRE(table.size() == 5);
  for (const auto& row : table) {
    const BifilarCheck c = check_bifilar_row(row);
    INFO(row.axis << ": computed " << c.computed_kgm2 << ", printed " << row.printed_kgm2 << ", range ["
                  << c.min_kgm2 << ", " << c.max_kgm2 << "]");
    if (row.axis == "I_x") {
      // 0.388 from the printed numbers, 11.8 % above the printed 0.347, far outside rounding;
      // the printed value needs T = 2.49 s, i.e. the I_z row's 2.48 s (see docs/PHYSICS.md).
      CHECK_FALSE(c.consistent);
      CHECK(c.relative_diff == Approx(0.118).margin(0.002));
      CHECK(c.period_for_printed_s == Approx(2.487).margin(0.002));
      BifilarRow swapped = row;
      swapped.period_s = 2.48;
      CHECK(check_bifilar_row(swapped).consistent);
    } else {
      CHECK(c.consistent);
    }
  }
  // I_y: every digit reproduced.
  CHECK(check_bifilar_row(table[1]).computed_kgm2 == Approx(1.131).margin(5e-4));
  // I_z is 4.2 % above the print, inside the rounding box only at its corner (b = 0.255).
  const BifilarCheck z = check_bifilar_row(table[2]);
  CHECK(z.relative_diff == Approx(0.042).margin(0.002));
  // ... or exactly (to 0.5 %) if the wires hung symmetric about the wheelbase centre, the CG
  // (l_f - l_r) / 2 = 5.5 cm behind it: the general form with R1 = b + e, R2 = b - e.
  const double e = (0.34 - 0.23) / 2;
  CHECK(bifilar_inertia(21.88, 2.48, 0.26 + e, 0.26 - e, 1.93) == Approx(1.124).epsilon(0.005));
}
