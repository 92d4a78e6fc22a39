// The paper's Magic Formula and the combined-slip tyre friction, against values computed
// with numpy (double) from the paper's formula and tyre table, plus the fast math they use.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "dynamics/fast_trig.hpp"
#include "dynamics/pacejka.hpp"

using mppi::PacejkaCoeffs;
using mppi::PacejkaParams;

TEST_CASE("fast_sincos, fast_atan and fast_sqrt against libm", "[physics][math]") {
  double sc_err = 0, atan_err = 0, sqrt_rel_err = 0;
  for (int i = -400000; i <= 400000; ++i) {
    const float x = i * 2.5e-3f;  // [-1000, 1000] rad: many turns of an unwrapped heading
    float s, c;
    mppi::fast_sincos(x, &s, &c);
    sc_err = std::max(sc_err, std::abs(s - std::sin(double(x))));
    sc_err = std::max(sc_err, std::abs(c - std::cos(double(x))));
  }
  for (int i = -200000; i <= 200000; ++i) {
    const float x = std::sinh(i * 1e-4f) ;  // dense near 0, out to +-2.4e8
    atan_err = std::max(atan_err, std::abs(mppi::fast_atan(x) - std::atan(double(x))));
  }
  for (int i = 1; i < 200000; ++i) {
    const float x = float(double(i) * i * 1e-6);  // (0, 4e4]
    sqrt_rel_err = std::max(sqrt_rel_err, std::abs(mppi::fast_sqrt(x) / std::sqrt(double(x)) - 1));
  }
  CHECK(sc_err < 1e-6);
  CHECK(atan_err < 1e-6);
  CHECK(sqrt_rel_err < 1e-6);
  CHECK(mppi::fast_sqrt(0.f) == 0.f);
  CHECK(mppi::fast_atan(0.f) == 0.f);
  // Exact quadrant handling at the reduction boundaries.
  float s, c;
  mppi::fast_sincos(-3.14159265f, &s, &c);
  CHECK(c == Approx(-1.0).margin(1e-6));
  mppi::fast_sincos(1.57079633f, &s, &c);
  CHECK(s == Approx(1.0).margin(1e-6));
}

TEST_CASE("Magic Formula mu(s) with the paper's tyre parameters", "[physics][pacejka]") {
  // numpy, double: D sin(C atan(B SE - E (B SE - atan SE))) + Sv, SE = s - Sh,
  // B 1.1559, C 1.1924, D 0.9956, E -0.8505, Sh -0.0540, Sv 0.1444.
  // By hand at s = 0: SE = 0.054, B SE = 0.062419, atan SE = 0.053948, inner = 0.062419 +
  // 0.8505 * 0.008471 = 0.069623, atan = 0.069511, sin(1.1924 * 0.069511) = 0.082792,
  // mu = 0.9956 * 0.082792 + 0.1444 = 0.22683.
  const struct {
    double s, mu;
  } cases[] = {{0, 0.22682578455},   {0.05, 0.302241052397}, {0.1, 0.37596912442},
               {0.2, 0.515496611031}, {0.5, 0.838122005879}, {1, 1.0704292032},
               {2, 1.13939570609},   {2.2101, 1.13999999999}, {5, 1.12409655823},
               {10, 1.11065481533},  {30, 1.1003166601}};
  const auto cd = PacejkaCoeffs<double>::from(PacejkaParams{});
  const auto cf = PacejkaCoeffs<float>::from(PacejkaParams{});
  for (const auto& c : cases) {
    INFO("s = " << c.s);
    CHECK(mppi::magic_formula_mu(c.s, cd) == Approx(c.mu).margin(1e-10));
    CHECK(mppi::magic_formula_mu(static_cast<float>(c.s), cf) == Approx(c.mu).margin(2e-6));
  }
  // The peak: max mu = 1.14 at s ~ 2.21 (numpy grid search); nothing above it.
  double best = 0;
  for (int i = 0; i <= 20000; ++i) best = std::max(best, mppi::magic_formula_mu(i * 1e-3, cd));
  CHECK(best == Approx(1.14).margin(1e-6));
}

TEST_CASE("Combined-slip tyre friction: paper slips with the documented regularisation",
          "[physics][pacejka]") {
  const auto cd = PacejkaCoeffs<double>::from(PacejkaParams{});
  const double floor = 2.5, inv_eps = 1 / 0.2;
  // numpy oracle: den = max(|wR|, 2.5), sx = (vx - wR)/den, sy = vy/den, s = |(sx, sy)|,
  // mu_k = -s_k mu(s) tanh(s / 0.2) / s.
  const struct {
    double vx, vy, rim, mux, muy;
  } cases[] = {
      {5, 0.5, 4.5, -0.212066793951, -0.212066793951},   // braking-ish, sliding left
      {8, -1.2, 9.0, 0.215109831202, 0.258131797442},    // driving, sliding right
      {3, 0, 0.0, -1.10375048684, 0.0},                  // locked wheel: denominator floor
      {1.0, 0.3, 1.5, 0.394426746331, -0.236656047799},  // rim speed below the floor
      {-2, 0.2, -2.2, -0.143044485591, -0.143044485591}, // rolling backwards, wheel faster
      {10, 0, 10, 0.0, 0.0},                             // free rolling: no force
  };
  for (const auto& c : cases) {
    INFO("vx " << c.vx << " vy " << c.vy << " rim " << c.rim);
    const auto f = mppi::tyre_friction(c.vx, c.vy, c.rim, floor, inv_eps, cd);
    CHECK(f.mu_x == Approx(c.mux).margin(1e-10));
    CHECK(f.mu_y == Approx(c.muy).margin(1e-10));
    const auto ff = mppi::tyre_friction<float>(c.vx, c.vy, c.rim, 2.5f, 5.f,
                                               PacejkaCoeffs<float>::from(PacejkaParams{}));
    CHECK(ff.mu_x == Approx(c.mux).margin(2e-6));
    CHECK(ff.mu_y == Approx(c.muy).margin(2e-6));
  }
  // Far from zero slip the force is the paper's -(s_k/s) mu(s): here s = 2.54, tanh(s/0.2) = 1
  // to 2e-11.
  const auto far = mppi::tyre_friction(20.0, 6.0, 6.0, floor, inv_eps, cd);
  const double sx = 14.0 / 6.0, sy = 1.0, s = std::hypot(sx, sy);
  CHECK(far.mu_x == Approx(-sx / s * mppi::magic_formula_mu(s, cd)).epsilon(1e-9));
  CHECK(far.mu_y == Approx(-sy / s * mppi::magic_formula_mu(s, cd)).epsilon(1e-9));
}

TEST_CASE("Tyre force goes to zero continuously at zero slip", "[physics][pacejka]") {
  const auto cd = PacejkaCoeffs<double>::from(PacejkaParams{});
  const double eps = 0.2;
  // At exactly zero slip: no force (the paper's s_k/s is 0/0 there, with mu(0) = 0.227).
  const auto zero = mppi::tyre_friction(7.0, 0.0, 7.0, 2.5, 1 / eps, cd);
  CHECK(zero.mu_x == 0.0);
  CHECK(zero.mu_y == 0.0);
  // Near zero, |mu_k| ~ |s_k| mu(0) / eps: linear, no jump (compare with the limit slope).
  double prev = 0;
  for (double sy : {1e-10, 1e-8, 1e-6, 1e-5, 1e-4, 1e-3}) {
    const auto f = mppi::tyre_friction(7.0, sy * 7.0, 7.0, 2.5, 1 / eps, cd);
    INFO("sy = " << sy);
    CHECK(-f.mu_y / sy == Approx(0.22682578455 / eps).epsilon(2e-2));
    CHECK(-f.mu_y > prev);  // monotone in the slip
    prev = -f.mu_y;
  }
  // The force direction opposes the slip in every direction around the origin.
  for (int k = 0; k < 16; ++k) {
    const double a = k * M_PI / 8, sx = 0.3 * std::cos(a), sy = 0.3 * std::sin(a);
    const auto f = mppi::tyre_friction(10.0 * (1 + sx), 10.0 * sy, 10.0, 2.5, 1 / eps, cd);
    CHECK(f.mu_x * sx + f.mu_y * sy < 0);
    CHECK(std::abs(f.mu_x * sy - f.mu_y * sx) < 1e-12);  // parallel to the slip
  }
}

TEST_CASE("PacejkaParams::is_valid", "[physics][pacejka]") {
  std::string why;
  CHECK(PacejkaParams{}.is_valid(&why));
  PacejkaParams p;
  p.D = -1;
  CHECK_FALSE(p.is_valid(&why));
  CHECK(why.find("D") != std::string::npos);
  p = {};
  p.Sv = -0.5;  // mu(0) < 0: the tyre would push along the slip
  CHECK_FALSE(p.is_valid(&why));
  CHECK(why.find("mu(s)") != std::string::npos);
  p = {};
  p.B = std::nan("");
  CHECK_FALSE(p.is_valid(&why));
}
