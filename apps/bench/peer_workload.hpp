#pragma once
// The cross-implementation workload of the MPPI-Generic benchmark (MPPI-Generic website,
// "Benchmarks", Table 1; settings in ACDSLab/MPPI_Paper_Example_Code test/include/test/common.hpp):
// differential drive (r = L = 1 m; v in [-0.35, 0.5] m/s, omega in [-0.5, 0.5] rad/s), forward
// Euler at dt = 0.02 s, T = 100, lambda = 1, control std 0.2, one iteration per call; cost =
// goal (weight 5, power 1) + goal angle (weight 5, power 1) + obstacles (critical weight 20,
// inflation radius 0.1 m, collision margin 0.1 m) on an 11 m x 11 m map at 0.1 m per cell with
// three square obstacles of value 250 at (8, 8) 0.4 m, (4, 6) 0.5 m, (6, 5) 0.3 m; start
// (1, 1, 0), goal (10, 10, 0).
#include <memory>
#include <vector>

#include "costs/goal_obstacle_cost.hpp"
#include "dynamics/diff_drive.hpp"
#include "mppi/controller_options.hpp"
#include "mppi/cost_map.hpp"

namespace mppi::bench {

inline std::shared_ptr<const CostMap> peer_cost_map() {
  static const std::shared_ptr<const CostMap> map = std::make_shared<const CostMap>(
      make_square_obstacle_map(11.f, 0.1f, {{8.f, 8.f, 0.4f}, {4.f, 6.f, 0.5f}, {6.f, 5.f, 0.3f}}, 250.f));
  return map;
}

inline GoalObstacleCost peer_cost() { return GoalObstacleCost(peer_cost_map(), GoalObstacleCostParams{}); }

inline DiffDrive peer_model() { return DiffDrive(DiffDriveParams{}); }

inline ControllerOptions peer_options(int num_samples, int horizon, int threads) {
  ControllerOptions o;
  o.num_samples = num_samples;
  o.horizon = horizon;
  o.dt_s = 0.02f;
  o.iterations = 1;
  o.lambda = 1.f;
  // MPPI-Generic's Gaussian sampling adds the likelihood-ratio control cost with coefficient
  // lambda (alpha = 0); Nav2 adds gamma = 0.015. Either costs the same to compute.
  o.gamma = 1.f;
  o.noise_std = {0.2f, 0.2f};
  o.control_min = {-0.35f, -0.5f};
  o.control_max = {0.5f, 0.5f};
  o.safe_control = {0.f, 0.f};
  o.seed = 1;
  o.num_threads = threads;
  return o;
}

inline std::vector<float> peer_start_state() { return {1.f, 1.f, 0.f}; }

}  // namespace mppi::bench
