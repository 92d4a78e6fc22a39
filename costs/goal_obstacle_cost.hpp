#pragma once
// Goal + goal-angle + obstacle running cost of the MPPI-Generic / Nav2 cross-implementation
// benchmark (Nav2's GoalCritic, GoalAngleCritic and ObstaclesCritic as MPPI-Generic's
// ComparisonCost re-implements them), for any model whose state starts with (x, y, yaw):
//   goal     = (w_g d)^p_g                       d = distance to the goal [m]
//   angle    = (w_a |wrap(yaw_goal - yaw)|)^p_a  (both only while d < goal_distance_threshold)
//   obstacle = f(c)  with c the cost-map value (Nav2 costmap units 0..255) at (x, y):
//     c < 1: 0 (free);  c >= lethal_value: collision_cost;  otherwise the distance to the
//     obstacle implied by Nav2's inflation decay, dist = (s r_min - ln c + ln 253) / s - r_min,
//     gives (critical_weight (margin - dist))^p if dist < margin, else, unless d < near_goal,
//     (repulsion_weight max(0, inflation_radius - dist))^p.
// f depends on the cell only, so it is tabulated per cell at construction (two tables: the
// critical part and the repulsive part that the near-goal test switches off): the hot loop
// does one index computation and two gathers per lane.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "base/batch.hpp"
#include "base/error.hpp"
#include "dynamics/fast_trig.hpp"
#include "mppi/cost_map.hpp"

namespace mppi {

struct GoalObstacleCostParams {
  float goal_x_m = 10.f;                     // goal position x [m]
  float goal_y_m = 10.f;                     // goal position y [m]
  float goal_yaw_rad = 0.f;                  // goal heading [rad]
  float goal_weight = 5.f;                   // w_g [1/m]
  int goal_power = 1;                        // p_g (1..4)
  float goal_angle_weight = 5.f;             // w_a [1/rad]
  int goal_angle_power = 1;                  // p_a (1..4)
  float goal_distance_threshold_m = 1000.f;  // goal terms count only closer than this [m]
  float critical_weight = 20.f;              // Nav2 ObstaclesCritic critical_weight [1/m]
  float repulsion_weight = 0.f;              // Nav2 repulsion_weight [1/m]
  float inflation_radius_m = 0.1f;           // Nav2 inflation_radius [m] (repulsive term)
  float collision_margin_m = 0.1f;           // Nav2 collision_margin_distance [m]
  float cost_scaling_factor = 1.f;           // Nav2 cost_scaling_factor s [1/m] (> 0)
  float inscribed_radius_m = 0.f;            // r_min [m] (the benchmark uses 0)
  float near_goal_distance_m = 0.5f;         // no repulsive term closer to the goal than this [m]
  int obstacle_power = 1;                    // p (1..4)
  float collision_cost = 10000.f;            // cost of a cell at/above lethal_value
  float lethal_value = 253.f;                // Nav2 INSCRIBED_INFLATED_OBSTACLE

  // True if the numbers are finite, weights >= 0, powers in 1..4, s > 0; else false + why.
  bool is_valid(std::string* why = nullptr) const {
    auto fail = [why](const std::string& reason) {
      if (why) *why = reason;
      return false;
    };
    const std::pair<const char*, float> finite[] = {
        {"goal_x_m", goal_x_m}, {"goal_y_m", goal_y_m}, {"goal_yaw_rad", goal_yaw_rad},
        {"inflation_radius_m", inflation_radius_m}, {"collision_margin_m", collision_margin_m},
        {"inscribed_radius_m", inscribed_radius_m}, {"near_goal_distance_m", near_goal_distance_m},
        {"lethal_value", lethal_value}};
    for (const auto& [name, v] : finite)
      if (!std::isfinite(v)) return fail(std::string(name) + " must be finite");
    const std::pair<const char*, float> weights[] = {
        {"goal_weight", goal_weight}, {"goal_angle_weight", goal_angle_weight},
        {"critical_weight", critical_weight}, {"repulsion_weight", repulsion_weight},
        {"collision_cost", collision_cost}};
    for (const auto& [name, w] : weights)
      if (!std::isfinite(w) || w < 0.f) return fail(std::string(name) + " must be finite and >= 0");
    const std::pair<const char*, int> powers[] = {
        {"goal_power", goal_power}, {"goal_angle_power", goal_angle_power}, {"obstacle_power", obstacle_power}};
    for (const auto& [name, p] : powers)
      if (p < 1 || p > 4) return fail(std::string(name) + " must be in 1..4");
    if (!(goal_distance_threshold_m > 0.f)) return fail("goal_distance_threshold_m must be > 0");
    if (!std::isfinite(cost_scaling_factor) || !(cost_scaling_factor > 0.f))
      return fail("cost_scaling_factor must be finite and > 0");
    return true;
  }
};

// One evaluation split into its terms (total = goal + angle + obstacle; +inf for a NaN state).
struct GoalObstacleTerms {
  float goal = 0.f;
  float goal_angle = 0.f;
  float obstacle = 0.f;
  float total = 0.f;
};

class GoalObstacleCost {
 public:
  // map: Nav2-style cell values (0 free .. 255). Throws mppi::Error if map is null or the
  // parameters are invalid.
  explicit GoalObstacleCost(std::shared_ptr<const CostMap> map, GoalObstacleCostParams params = {})
      : map_(std::move(map)), params_(params) {
    if (!map_) throw Error("GoalObstacleCost: cost map is null");
    std::string why;
    if (!params_.is_valid(&why)) throw Error("GoalObstacleCost: invalid parameters: " + why);
    const std::vector<float>& v = map_->values();
    critical_ = std::make_shared<std::vector<float>>(v.size());
    repulsive_ = std::make_shared<std::vector<float>>(v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
      cell_cost(params_, v[i], &(*critical_)[i], &(*repulsive_)[i]);
  }

  const GoalObstacleCostParams& params() const noexcept { return params_; }
  const CostMap& map() const noexcept { return *map_; }
  const std::shared_ptr<const CostMap>& map_ptr() const noexcept { return map_; }

  // The obstacle cost of a cell value, split into the part that always counts and the
  // repulsive part that is dropped near the goal (double precision, then rounded).
  static void cell_cost(const GoalObstacleCostParams& p, float value, float* critical, float* repulsive) {
    *critical = 0.f;
    *repulsive = 0.f;
    if (value < 1.f) return;  // free space
    if (value >= p.lethal_value) {
      *critical = p.collision_cost;
      return;
    }
    const double s = p.cost_scaling_factor, r_min = p.inscribed_radius_m;
    const double dist = (s * r_min - std::log(static_cast<double>(value)) + std::log(253.0)) / s - r_min;
    if (dist < p.collision_margin_m)
      *critical = static_cast<float>(std::pow(p.critical_weight * (p.collision_margin_m - dist), p.obstacle_power));
    else
      *repulsive = static_cast<float>(std::pow(
          p.repulsion_weight * std::max(0.0, p.inflation_radius_m - dist), p.obstacle_power));
  }

  // Plain-data view for the lane loop (copied into locals so the compiler keeps it in registers).
  struct View {
    CostMap::View map;
    const float* critical;
    const float* repulsive;
  };
  View view() const noexcept { return {map_->view(), critical_->data(), repulsive_->data()}; }

  // b^P, P known at compile time (a run-time power inside the lane loop stops GCC 12 from
  // vectorising it; accumulate() dispatches on the powers once per call instead).
  template <int P>
  static float ipow(float b) noexcept {
    float r = b;
    for (int i = 1; i < P; ++i) r *= b;
    return r;
  }
  static float pow_int(float b, int p) noexcept {
    float r = b;
    for (int i = 1; i < p; ++i) r *= b;
    return r;
  }

  // All terms at one state, goal powers PG, PA (0 = take them from p at run time).
  // Branch-free; inlined into the lane loop.
  // kRepulsive = false drops the repulsive table (repulsion_weight = 0: it is all zeros), which
  // saves a gather per lane.
  template <int PG = 0, int PA = 0, bool kRepulsive = true>
  static GoalObstacleTerms terms(const GoalObstacleCostParams& p, const View& v, float x_m,
                                 float y_m, float yaw_rad) noexcept {
    GoalObstacleTerms c;
    const float dx = x_m - p.goal_x_m, dy = y_m - p.goal_y_m;
    // std::sqrt: one vsqrtps (the library builds with -fno-math-errno, so it vectorises),
    // correctly rounded, and cheaper than fast_sqrt's three Newton steps here
    const float d = std::sqrt(dx * dx + dy * dy);
    const float consider = static_cast<float>(static_cast<int>(d < p.goal_distance_threshold_m));
    // yaw difference wrapped to [-pi, pi]: subtract the nearest whole number of turns
    const float diff = p.goal_yaw_rad - yaw_rad;
    constexpr float kInvTwoPi = 0.159154943091895336f, kTwoPi = 6.28318530717958648f;
    const float turns = static_cast<float>(static_cast<int>(diff * kInvTwoPi + std::copysign(0.5f, diff)));
    const float angle = std::fabs(diff - turns * kTwoPi);
    const float g = p.goal_weight * d, a = p.goal_angle_weight * angle;
    if constexpr (PG > 0) c.goal = consider * ipow<PG>(g);
    else c.goal = consider * pow_int(g, p.goal_power);
    if constexpr (PA > 0) c.goal_angle = consider * ipow<PA>(a);
    else c.goal_angle = consider * pow_int(a, p.goal_angle_power);
    const int cell = v.map.row_of(y_m) * v.map.width + v.map.col_of(x_m);
    const float far = static_cast<float>(static_cast<int>(!(d < p.near_goal_distance_m)));
    if constexpr (kRepulsive) c.obstacle = v.critical[cell] + far * v.repulsive[cell];
    else c.obstacle = v.critical[cell];
    const float poison = 0.f * (x_m + y_m + yaw_rad);  // NaN if the state is not finite
    c.total = std::min(std::numeric_limits<float>::infinity(), c.goal + c.goal_angle + c.obstacle + poison);
    return c;
  }

  // cost[j] += q(x_j) for every lane j; x rows 0, 1, 2 are x, y, yaw.
  template <int Nx, int Nu, int W>
  void accumulate(ConstBatch<Nx, W> x, ConstBatch<Nu, W> /*u*/, int /*t*/, float* cost) const noexcept {
    static_assert(Nx >= 3, "GoalObstacleCost needs (x, y, yaw) as the first states");
    if (params_.goal_power == 1 && params_.goal_angle_power == 1 && params_.repulsion_weight == 0.f)
      return lanes<1, 1, false, Nx, W>(x, cost);  // the benchmark's setting
    switch (params_.goal_power * 8 + params_.goal_angle_power) {
      case 1 * 8 + 1: return lanes<1, 1, true, Nx, W>(x, cost);
      case 1 * 8 + 2: return lanes<1, 2, true, Nx, W>(x, cost);
      case 2 * 8 + 1: return lanes<2, 1, true, Nx, W>(x, cost);
      case 2 * 8 + 2: return lanes<2, 2, true, Nx, W>(x, cost);
      default: return lanes<0, 0, true, Nx, W>(x, cost);  // other powers: not vectorised
    }
  }

  // q at one state (x, y, yaw, ...).
  float evaluate(const float* s, GoalObstacleTerms* terms_out = nullptr) const noexcept {
    const GoalObstacleTerms c = terms(params_, view(), s[0], s[1], s[2]);
    if (terms_out) *terms_out = c;
    return c.total;
  }

 private:
  template <int PG, int PA, bool kRepulsive, int Nx, int W>
  void lanes(ConstBatch<Nx, W> x, float* cost) const noexcept {
    const GoalObstacleCostParams p = params_;
    const View v = view();
    const float* px = x[0];
    const float* py = x[1];
    const float* pyaw = x[2];
    MPPI_SIMD_LOOP for (int j = 0; j < W; ++j) cost[j] += terms<PG, PA, kRepulsive>(p, v, px[j], py[j], pyaw[j]).total;
  }

  std::shared_ptr<const CostMap> map_;
  GoalObstacleCostParams params_;
  // per-cell tables, shared and immutable so that copies of the cost are cheap
  std::shared_ptr<std::vector<float>> critical_, repulsive_;
};

// The benchmark's 11 m x 11 m map at 0.1 m per cell, origin (0, 0), value 0 except the given
// square obstacles (lower-left corner and side [m], value `obstacle_value`); cells are
// [int(corner / res), int(corner / res) + int(side / res)) per axis, computed in float like
// MPPI_Paper_Example_Code's test/include/test/common.hpp (row = y cell, col = x cell).
struct SquareObstacle {
  float x_m, y_m, side_m;
};
inline CostMap make_square_obstacle_map(float size_m, float resolution_m,
                                        const std::vector<SquareObstacle>& obstacles,
                                        float obstacle_value) {
  const int n = static_cast<int>(size_m / resolution_m);
  std::vector<float> values(static_cast<std::size_t>(n) * n, 0.f);
  for (const SquareObstacle& o : obstacles) {
    const int cx = static_cast<int>(o.x_m / resolution_m);
    const int cy = static_cast<int>(o.y_m / resolution_m);
    const int side = static_cast<int>(o.side_m / resolution_m);
    for (int row = std::max(0, cy); row < std::min(n, cy + side); ++row)
      for (int col = std::max(0, cx); col < std::min(n, cx + side); ++col)
        values[static_cast<std::size_t>(row) * n + col] = obstacle_value;
  }
  return CostMap(0.f, size_m, 0.f, size_m, 1.f / resolution_m, std::move(values));
}

}  // namespace mppi
