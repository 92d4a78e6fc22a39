// Cost parameters and the cost map change while the controller runs: after the change the
// backend's rollout costs equal those of a backend built with the new cost from the start
// (CPU: exactly; Vulkan: within the parity tolerance), the plan is kept, and a bad key or
// value changes nothing.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "mppi/controller.hpp"
#include "mppi/cost_map.hpp"
#include "mppi/cpu_backend.hpp"
#include "test_data.hpp"

namespace {

std::shared_ptr<const mppi::CostMap> gazebo_map() {
  static const auto map = std::make_shared<const mppi::CostMap>(
      mppi::CostMap::load_npz(std::string(MPPI_TEST_DATA_DIR) + "/autorally/maps/gazebo/gazebo_costmap.npz"));
  return map;
}

constexpr int kSamples = 64, kHorizon = 40;

// Random clamped controls, T x nu x padded.
std::vector<float> random_controls(int padded) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<float> c(static_cast<std::size_t>(kHorizon) * 2 * padded);
  for (float& v : c) v = u(rng);
  return c;
}

std::vector<float> rollout_costs(mppi::Backend& b) {
  const std::vector<float> x0 = {-8.5f, -8.9f, 2.3561945f, 5.f, 0.f, 0.1f, 0.f};
  const std::vector<float> controls = random_controls(b.shape().padded_samples);
  std::vector<float> costs(static_cast<std::size_t>(b.shape().padded_samples));
  b.rollout(x0, controls, costs);
  costs.resize(kSamples);
  return costs;
}

mppi::CpuBackend<mppi::KinematicBicycle, mppi::AutoRallyCost> cpu_backend(const mppi::AutoRallyCost& cost) {
  return {mppi::KinematicBicycle{}, cost, kSamples, kHorizon, 0.02f, 1};
}

}  // namespace

TEST_CASE("cost update: a changed parameter gives the costs of a cost built with it", "[costs][update]") {
  const mppi::AutoRallyCost original(gazebo_map());
  mppi::AutoRallyCostParams p9;
  p9.target_speed_mps = 9.f;
  p9.slip_weight = 3.f;
  auto changed = cpu_backend(original);
  auto reference = cpu_backend(mppi::AutoRallyCost(gazebo_map(), p9));
  const std::vector<float> before = rollout_costs(changed);
  std::string why;
  REQUIRE(changed.set_cost_param("target_speed_mps", 9.0, &why));
  REQUIRE(changed.set_cost_param("slip_weight", 3.0, &why));
  const std::vector<float> after = rollout_costs(changed);
  CHECK(after == rollout_costs(reference));
  CHECK(after != before);
}

TEST_CASE("cost update: a bad key or value is refused and changes nothing", "[costs][update]") {
  auto b = cpu_backend(mppi::AutoRallyCost(gazebo_map()));
  const std::vector<float> before = rollout_costs(b);
  std::string why;
  CHECK_FALSE(b.set_cost_param("target_speed", 9.0, &why));
  CHECK_THAT(why, Catch::Contains("unknown cost parameter 'target_speed'"));
  CHECK_FALSE(b.set_cost_param("speed_weight", -1.0, &why));
  CHECK_THAT(why, Catch::Contains("speed_weight") && Catch::Contains(">= 0"));
  CHECK_FALSE(b.set_cost_param("target_speed_mps", std::nan(""), &why));
  CHECK_FALSE(b.set_cost_param("crash_discount", 1.5, &why));
  CHECK_FALSE(b.set_cost_map(nullptr, &why));
  CHECK(rollout_costs(b) == before);
  // +inf turns the roll check off: allowed where the range says so.
  CHECK(b.set_cost_param("max_roll_rad", INFINITY, &why));
}

TEST_CASE("cost update: a new cost map gives the costs of a cost built with it", "[costs][update]") {
  auto b = cpu_backend(mppi::AutoRallyCost(gazebo_map()));
  // The same map shifted by 1 m in x: another region under the same rollouts.
  const mppi::CostMap& m = *gazebo_map();
  const auto shifted_ptr = std::make_shared<const mppi::CostMap>(
      m.x_min_m() + 1.f, m.x_max_m() + 1.f, m.y_min_m(), m.y_max_m(), m.pixels_per_meter(), m.values());
  auto reference = cpu_backend(mppi::AutoRallyCost(shifted_ptr));
  std::string why;
  REQUIRE(b.set_cost_map(shifted_ptr, &why));
  CHECK(rollout_costs(b) == rollout_costs(reference));
}

TEST_CASE("cost update: the controller keeps its plan", "[costs][update]") {
  mppi::ControllerOptions o;
  o.num_samples = 256;
  o.horizon = 30;
  o.num_threads = 1;
  mppi::Controller c = mppi::make_cpu_controller(mppi::KinematicBicycle{}, mppi::AutoRallyCost(gazebo_map()), o);
  const std::vector<float> x0 = {-8.5f, -8.9f, 2.3561945f, 5.f, 0.f, 0.1f, 0.f};
  for (int i = 0; i < 5; ++i) c.step(x0);
  const std::vector<float> plan(c.nominal().begin(), c.nominal().end());
  std::string why;
  REQUIRE(c.set_cost_param("target_speed_mps", 8.0, &why));
  CHECK(std::vector<float>(c.nominal().begin(), c.nominal().end()) == plan);
  CHECK_FALSE(c.set_cost_param("nonsense", 1.0, &why));
}
