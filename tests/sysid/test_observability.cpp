// The observability check flags constructed unobservable states and parameter pairs.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "sysid/observability.hpp"

using namespace mppi::sysid;

TEST_CASE("observability of a double integrator: position vs velocity measured", "[sysid][observability]") {
  const double dt = 0.1;
  auto f = [dt](const Vec& x, const Vec&) -> Vec {
    Vec o(2);
    o << x(0) + dt * x(1), x(1);
    return o;
  };
  auto pos = [](const Vec& x, const Vec&) -> Vec { return x.head(1); };
  auto vel = [](const Vec& x, const Vec&) -> Vec { return x.tail(1); };
  const Vec x0 = Vec::Constant(2, 1.0);
  const auto a = observability(f, pos, {x0}, {Vec()});
  CHECK(a.full_rank());
  const auto b = observability(f, vel, {x0}, {Vec()});
  CHECK(b.rank == 1);
  REQUIRE(b.unobservable == std::vector<int>{0});
  CHECK(std::abs(b.null_space(0, 0)) == Approx(1.0));
}

TEST_CASE("observability flags two parameters that enter only as a product", "[sysid][observability]") {
  // x' = -(a b) x + u: only a*b can be identified. Joint state [x, a, b].
  const double dt = 0.05;
  auto f = [dt](const Vec& s, const Vec& u) -> Vec {
    Vec o = s;
    o(0) = s(0) + dt * (-s(1) * s(2) * s(0) + u(0));
    return o;
  };
  auto h = [](const Vec& s, const Vec&) -> Vec { return s.head(1); };
  std::vector<Vec> xs, us;
  Vec s(3);
  s << 1.0, 2.0, 0.5;
  for (int k = 0; k < 50; ++k) {
    Vec u(1);
    u << std::sin(0.3 * k);
    xs.push_back(s);
    us.push_back(u);
    s = f(s, u);
  }
  const auto rep = observability(f, h, xs, us);
  CHECK(rep.rank == 2);
  CHECK(rep.unobservable == std::vector<int>{1, 2});
  // Null direction ~ (0, a, -b) normalised (d(ab) = b da + a db = 0).
  const double a = 2.0, b = 0.5, nrm = std::hypot(a, b);
  CHECK(std::abs(rep.null_space(1, 0)) == Approx(a / nrm).margin(1e-4));
  CHECK(std::abs(rep.null_space(2, 0)) == Approx(b / nrm).margin(1e-4));
  CHECK(rep.describe({"x", "a", "b"}).find("not identifiable: a, b") != std::string::npos);

  // Fix b (drop it from the state): observable.
  auto f2 = [dt](const Vec& s2, const Vec& u) -> Vec {
    Vec o = s2;
    o(0) = s2(0) + dt * (-s2(1) * 0.5 * s2(0) + u(0));
    return o;
  };
  std::vector<Vec> xs2;
  for (const Vec& x : xs) xs2.push_back(x.head(2));
  CHECK(observability(f2, h, xs2, us).full_rank());
}
