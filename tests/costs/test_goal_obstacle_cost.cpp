// The goal / goal-angle / obstacle cost against a naive double-precision reference written
// from the Nav2 / MPPI-Generic formulas, and the benchmark map's obstacle cells.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "costs/goal_obstacle_cost.hpp"
#include "error_of.hpp"

using mppi::CostMap;
using mppi::GoalObstacleCost;
using mppi::GoalObstacleCostParams;

namespace {
std::shared_ptr<const CostMap> bench_map() {
  return std::make_shared<const CostMap>(mppi::make_square_obstacle_map(
      11.f, 0.1f, {{8.f, 8.f, 0.4f}, {4.f, 6.f, 0.5f}, {6.f, 5.f, 0.3f}}, 250.f));
}

// Naive reference: cell by floor with clamping, Nav2's distance from the inflation decay.
double reference(const GoalObstacleCostParams& p, const CostMap& m, double x, double y, double yaw) {
  const int col = std::clamp(static_cast<int>(std::floor(x / 0.1)), 0, m.width() - 1);
  const int row = std::clamp(static_cast<int>(std::floor(y / 0.1)), 0, m.height() - 1);
  const double c = m.at(row, col);
  const double d = std::hypot(x - p.goal_x_m, y - p.goal_y_m);
  double obstacle = 0;
  if (c >= p.lethal_value) {
    obstacle = p.collision_cost;
  } else if (c >= 1) {
    const double s = p.cost_scaling_factor, r = p.inscribed_radius_m;
    const double dist = (s * r - std::log(c) + std::log(253.0)) / s - r;
    if (dist < p.collision_margin_m)
      obstacle = std::pow(p.critical_weight * (p.collision_margin_m - dist), p.obstacle_power);
    else if (d >= p.near_goal_distance_m)
      obstacle = std::pow(p.repulsion_weight * std::max(0.0, p.inflation_radius_m - dist), p.obstacle_power);
  }
  double goal = 0, angle = 0;
  if (d < p.goal_distance_threshold_m) {
    goal = std::pow(p.goal_weight * d, p.goal_power);
    angle = std::pow(p.goal_angle_weight * std::abs(std::remainder(p.goal_yaw_rad - yaw, 2 * M_PI)),
                     p.goal_angle_power);
  }
  return goal + angle + obstacle;
}

void check_batch(const GoalObstacleCost& cost, std::uint32_t seed) {
  constexpr int W = mppi::kChunk;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-1.f, 12.f), yaw(-20.f, 20.f);
  std::vector<float> x(3 * W), acc(W, 0.f);
  for (int j = 0; j < W; ++j) {
    // half the lanes on or next to an obstacle cell
    const bool near = j % 2 == 0;
    x[j] = near ? 8.013f + 0.05f * static_cast<float>(j % 10) : pos(rng);  // off cell edges
    x[W + j] = near ? 7.913f + 0.05f * static_cast<float>(j / 10) : pos(rng);
    x[2 * W + j] = yaw(rng);
  }
  const float u[2 * W] = {};
  cost.accumulate<3, 2, W>(mppi::ConstBatch<3, W>{x.data()}, mppi::ConstBatch<2, W>{u}, 0, acc.data());
  int on_obstacle = 0;
  for (int j = 0; j < W; ++j) {
    const double ref = reference(cost.params(), cost.map(), x[j], x[W + j], x[2 * W + j]);
    INFO("lane " << j << " at (" << x[j] << ", " << x[W + j] << ", " << x[2 * W + j] << ")");
    CHECK(acc[j] == Approx(ref).epsilon(2e-5).margin(1e-4));
    on_obstacle += cost.map().lookup(x[j], x[W + j]) > 0.f;
  }
  CHECK(on_obstacle >= 5);  // the test does exercise the obstacle term
}
}  // namespace

TEST_CASE("Benchmark map: three square obstacles of 250 on 110 x 110 cells", "[goalcost]") {
  const auto map = bench_map();
  REQUIRE(map->width() == 110);
  REQUIRE(map->height() == 110);
  int cells = 0;
  for (float v : map->values()) cells += v == 250.f;
  CHECK(cells == 4 * 4 + 5 * 5 + 3 * 3);
  CHECK(map->lookup(8.05f, 8.05f) == 250.f);
  CHECK(map->lookup(8.35f, 8.35f) == 250.f);
  CHECK(map->lookup(8.45f, 8.35f) == 0.f);
  CHECK(map->lookup(4.45f, 6.45f) == 250.f);
  CHECK(map->lookup(6.25f, 5.25f) == 250.f);
  CHECK(map->lookup(1.f, 1.f) == 0.f);
}

TEST_CASE("GoalObstacleCost matches the naive reference (benchmark weights)", "[goalcost]") {
  const GoalObstacleCost cost(bench_map());
  check_batch(cost, 1);
  check_batch(cost, 2);
  // on an obstacle cell: critical_weight (margin - ln(253 / 250)), closed form
  const float s[3] = {8.1f, 8.1f, 0.f};
  mppi::GoalObstacleTerms terms;
  cost.evaluate(s, &terms);
  CHECK(terms.obstacle == Approx(20.0 * (0.1 - std::log(253.0 / 250.0))).epsilon(1e-6));
  CHECK(terms.goal == Approx(5.0 * std::hypot(1.9, 1.9)).epsilon(1e-6));
}

TEST_CASE("GoalObstacleCost other settings: powers, repulsion near the goal, lethal cells", "[goalcost]") {
  std::vector<float> values(110 * 110, 0.f);
  for (int i = 0; i < 110 * 110; ++i) values[i] = static_cast<float>((i * 7) % 256);  // every value
  const auto map = std::make_shared<const CostMap>(0.f, 11.f, 0.f, 11.f, 10.f, values);
  GoalObstacleCostParams p;
  p.goal_x_m = 5.f;
  p.goal_y_m = 5.f;
  p.goal_yaw_rad = 1.f;
  p.near_goal_distance_m = 3.f;
  p.repulsion_weight = 3.f;
  p.inflation_radius_m = 2.f;
  p.cost_scaling_factor = 2.f;
  p.inscribed_radius_m = 0.05f;
  for (int pg : {1, 2, 3}) {
    p.goal_power = pg;
    p.goal_angle_power = 3 - pg + 1;
    p.obstacle_power = pg;
    INFO("goal power " << pg);
    check_batch(GoalObstacleCost(map, p), 10 + pg);
  }
}

TEST_CASE("GoalObstacleCost: NaN state costs +inf, bad settings throw", "[goalcost]") {
  const GoalObstacleCost cost(bench_map());
  const float s[3] = {NAN, 1.f, 0.f};
  CHECK(cost.evaluate(s) == std::numeric_limits<float>::infinity());
  GoalObstacleCostParams p;
  p.goal_power = 0;
  CHECK_THAT(mppi::test::error_of([&] { GoalObstacleCost(bench_map(), p); }), Catch::Contains("goal_power"));
  p = {};
  p.critical_weight = -1.f;
  CHECK_THAT(mppi::test::error_of([&] { GoalObstacleCost(bench_map(), p); }), Catch::Contains("critical_weight"));
  CHECK_THAT(mppi::test::error_of([] { GoalObstacleCost(nullptr); }), Catch::Contains("null"));
}
