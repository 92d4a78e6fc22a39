// The kinematic bicycle against closed forms: circle radius L / tan(delta), the discrete
// speed law, the yaw rate, and the batched step against the scalar one.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "dynamics/kinematic_bicycle.hpp"
#include "mppi/concepts.hpp"

using mppi::KinematicBicycle;
using mppi::KinematicBicycleParams;
namespace st = mppi::state;

static_assert(mppi::VehicleDynamics<KinematicBicycle>);

namespace {
std::array<float, 7> run(const KinematicBicycle& m, std::array<float, 7> x, float steer,
                         float throttle, float dt, int steps) {
  const float u[2] = {steer, throttle};
  for (int i = 0; i < steps; ++i)
    m.step<1>(mppi::Batch<7, 1>{x.data()}, mppi::ConstBatch<2, 1>{u}, dt, nullptr);
  return x;
}
}  // namespace

TEST_CASE("Kinematic bicycle drives a circle of radius L / tan(delta)", "[physics][kinematic]") {
  const KinematicBicycleParams p;
  const KinematicBicycle model(p);
  for (float steer : {1.f, 0.5f, -0.3f}) {
    INFO("steer " << steer);
    const double delta = steer * 0.38;
    const double radius = 0.57 / std::tan(delta);  // signed: centre on the left for steer > 0
    // Constant speed 5 m/s: throttle that balances the damping, a u = c v.
    const float v = 5.f, throttle = static_cast<float>(p.speed_damping_per_s * v / p.max_accel_mps2);
    std::array<float, 7> x{0, 0, 0, v, 0, 0, 0};
    const double dt = 1e-3;
    const int steps = static_cast<int>(2 * M_PI * std::abs(radius) / v / dt);  // one lap
    double worst = 0;
    for (int k = 0; k < steps; ++k) {
      x = run(model, x, steer, throttle, static_cast<float>(dt), 1);
      // Start at the origin heading +x: the centre is at (0, R).
      worst = std::max(worst, std::abs(std::hypot(x[st::kX], x[st::kY] - radius) - std::abs(radius)));
    }
    // Euler's radius drift after one lap is ~ pi * v dt / tan-free: |dR| <~ pi v dt = 0.016 m.
    CHECK(worst < 0.02 * std::max(1.0, std::abs(radius) / 3));
    CHECK(x[st::kVx] == Approx(v).epsilon(1e-5));
    CHECK(x[st::kYawRate] == Approx(v * std::tan(delta) / 0.57).epsilon(1e-5));
    CHECK(x[st::kVy] == 0.f);
    // A full lap brings the heading round by 2 pi.
    CHECK(std::abs(x[st::kYaw]) == Approx(2 * M_PI).epsilon(2e-3));
  }
}

TEST_CASE("Kinematic bicycle speed law: discrete Euler solution", "[physics][kinematic]") {
  const KinematicBicycleParams p;
  const KinematicBicycle model(p);
  // v_{n+1} = v_n + dt (a u - c v_n)  =>  v_n = v_ss + (v0 - v_ss)(1 - c dt)^n, v_ss = a u / c.
  const float dt = 0.02f, u = 0.65f, v0 = 2.f;
  const double v_ss = 4.0 * 0.65 / 0.2;  // 13 m/s
  const int n = 500;
  const auto x = run(model, {0, 0, 0, v0, 0, 0, 0}, 0.f, u, dt, n);
  CHECK(x[st::kVx] == Approx(v_ss + (v0 - v_ss) * std::pow(1 - 0.2 * 0.02, n)).epsilon(1e-5));
  CHECK(x[st::kY] == 0.f);
  // Straight line: x is the sum of the speeds times dt.
  double dist = 0, v = v0;
  for (int k = 0; k < n; ++k) {
    dist += v * dt;
    v += dt * (4.0 * u - 0.2 * v);
  }
  CHECK(x[st::kX] == Approx(dist).epsilon(1e-5));
  // Braking reverses the car eventually (negative throttle is a negative acceleration).
  const auto back = run(model, {0, 0, 0, 3.f, 0, 0, 0}, 0.f, -1.f, 0.02f, 500);
  CHECK(back[st::kVx] < -5.f);
}

TEST_CASE("Kinematic bicycle batched step equals scalar step and the double derivatives",
          "[physics][kinematic]") {
  const KinematicBicycle model;
  constexpr int W = 64;
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> U(-1, 1);
  std::vector<float> xb(7 * W), ub(2 * W);
  std::vector<std::array<float, 7>> lanes(W);
  for (int j = 0; j < W; ++j) {
    lanes[j] = {10 * U(rng), 10 * U(rng), 20 * U(rng), 8 + 8 * U(rng), 0, 0, 0};
    for (int i = 0; i < 7; ++i) xb[i * W + j] = lanes[j][i];
    ub[j] = 1.3f * U(rng);  // beyond +-1 too: clamped
    ub[W + j] = U(rng);
  }
  const float dt = 0.02f;
  model.step<W>(mppi::Batch<7, W>{xb.data()}, mppi::ConstBatch<2, W>{ub.data()}, dt, nullptr);
  for (int j = 0; j < W; ++j) {
    INFO("lane " << j);
    const auto s = run(model, lanes[j], ub[j], ub[W + j], dt, 1);
    double xd[7], dx[7];
    for (int i = 0; i < 7; ++i) xd[i] = lanes[j][i];
    const double ud[2] = {ub[j], ub[W + j]};
    model.derivatives(xd, ud, dx);
    for (int i : {0, 1, 2, 3}) {
      CHECK(xb[i * W + j] == Approx(s[i]).epsilon(1e-6).margin(1e-5));
      CHECK(xb[i * W + j] == Approx(xd[i] + dt * dx[i]).epsilon(1e-5).margin(1e-5));
    }
    // Yaw-rate state: v_new tan(delta) / L with the clamped steering.
    const double delta = std::clamp(double(ub[j]), -1.0, 1.0) * 0.38;
    CHECK(xb[5 * W + j] == Approx(xb[3 * W + j] * std::tan(delta) / 0.57).epsilon(1e-5).margin(1e-6));
    CHECK(xb[4 * W + j] == 0.f);
  }
}

TEST_CASE("KinematicBicycleParams validation", "[physics][kinematic]") {
  KinematicBicycleParams p;
  std::string why;
  CHECK(p.is_valid(&why));
  p.wheelbase_m = 0;
  CHECK_FALSE(p.is_valid(&why));
  CHECK(why.find("wheelbase_m") != std::string::npos);
  CHECK_THROWS_AS(KinematicBicycle(p), mppi::Error);
  p = {};
  p.max_steer_rad = 1.6;  // tan would blow up near pi/2
  CHECK_THROWS_WITH(KinematicBicycle(p), Catch::Contains("max_steer_rad"));
}
