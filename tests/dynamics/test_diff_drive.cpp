// The differential drive against a naive double-precision forward-Euler reference (std::cos,
// std::sin), a closed-form circle, and the wheel-speed relations.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "dynamics/diff_drive.hpp"
#include "error_of.hpp"
#include "mppi/concepts.hpp"

using mppi::DiffDrive;
using mppi::DiffDriveParams;

static_assert(mppi::Dynamics<DiffDrive>);

TEST_CASE("DiffDrive batch step matches a naive double Euler reference", "[diffdrive]") {
  const DiffDrive model;
  constexpr int W = mppi::kChunk, T = 100;
  const float dt = 0.02f;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> v(-0.35f, 0.5f), w(-0.5f, 0.5f), yaw0(-7.f, 7.f);
  std::vector<float> x(3 * W), u(2 * W * T);
  std::vector<std::array<double, 3>> ref(W);
  for (int j = 0; j < W; ++j) {
    x[j] = 1.f + 0.01f * j;
    x[W + j] = 1.f;
    x[2 * W + j] = yaw0(rng);
    ref[j] = {x[j], x[W + j], x[2 * W + j]};
  }
  for (auto& c : u) c = 0.f;
  for (int t = 0; t < T; ++t)
    for (int j = 0; j < W; ++j) {
      u[(t * 2 + 0) * W + j] = v(rng);
      u[(t * 2 + 1) * W + j] = w(rng);
    }
  for (int t = 0; t < T; ++t) {
    model.step<W>(mppi::Batch<3, W>{x.data()}, mppi::ConstBatch<2, W>{u.data() + t * 2 * W}, dt, nullptr);
    for (int j = 0; j < W; ++j) {
      const double uj[2] = {u[(t * 2 + 0) * W + j], u[(t * 2 + 1) * W + j]};
      double dx[3];
      DiffDrive::derivatives(ref[j].data(), uj, dx);
      // independent of derivatives(): the textbook unicycle
      REQUIRE(dx[0] == Approx(uj[0] * std::cos(ref[j][2])).margin(1e-12));
      for (int i = 0; i < 3; ++i) ref[j][i] += dt * dx[i];
    }
  }
  double worst = 0;
  for (int j = 0; j < W; ++j)
    for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(x[i * W + j] - ref[j][i]));
  CHECK(worst < 2e-5);  // float rounding over 100 steps
}

TEST_CASE("DiffDrive at constant (v, omega) drives a circle of radius v / omega", "[diffdrive]") {
  const DiffDrive model;
  const float u[2] = {0.5f, 0.25f};  // R = 2 m, centre (0, 2) from the origin heading +x
  float x[3] = {0.f, 0.f, 0.f};
  const float dt = 1e-3f;
  const int steps = static_cast<int>(2 * M_PI / 0.25 / dt);
  double worst = 0;
  for (int i = 0; i < steps; ++i) {
    model.step<1>(mppi::Batch<3, 1>{x}, mppi::ConstBatch<2, 1>{u}, dt, nullptr);
    worst = std::max(worst, std::abs(std::hypot(x[0], x[1] - 2.0) - 2.0));
  }
  CHECK(worst < 2e-3);  // Euler drift ~ pi v dt over one lap
  CHECK(x[2] == Approx(2 * M_PI).epsilon(1e-3));
}

TEST_CASE("DiffDrive wheel speeds <-> body speeds", "[diffdrive]") {
  const DiffDrive model(DiffDriveParams{0.5, 2.0});
  double v, w, l, r;
  model.body_from_wheels(1.0, 3.0, &v, &w);  // r (1 + 3) / 2, r (3 - 1) / L
  CHECK(v == Approx(1.0));
  CHECK(w == Approx(0.5));
  model.wheels_from_body(v, w, &l, &r);
  CHECK(l == Approx(1.0));
  CHECK(r == Approx(3.0));
  CHECK_THAT(mppi::test::error_of([] { DiffDrive(DiffDriveParams{0.0, 1.0}); }),
             Catch::Contains("wheel_radius_m"));
  CHECK_THAT(mppi::test::error_of([] { DiffDrive(DiffDriveParams{1.0, NAN}); }),
             Catch::Contains("wheel_base_m"));
}
