// The Vulkan backend's cost changes while it runs (a parameter, a cost map of the same size):
// its rollout costs then equal the CPU backend's built with the new cost, within the parity
// tolerance (1e-3 relative); a map of another size is refused and changes nothing.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "dynamics/single_track.hpp"
#include "mppi/cpu_backend.hpp"
#include "vulkan/vulkan_backend.hpp"
#include "test_data.hpp"
#include "vulkan/vulkan_test_util.hpp"

namespace {

constexpr int kSamples = 100, kHorizon = 60;

std::shared_ptr<const mppi::CostMap> gazebo_map() {
  static const auto map = std::make_shared<const mppi::CostMap>(
      mppi::CostMap::load_npz(std::string(MPPI_TEST_DATA_DIR) + "/autorally/maps/gazebo/gazebo_costmap.npz"));
  return map;
}

std::vector<float> costs_of(mppi::Backend& b) {
  std::vector<float> x0(mppi::SingleTrack::kNx, 0.f);
  x0[0] = -8.5f, x0[1] = -8.9f, x0[2] = 2.3561945f, x0[3] = 5.f;
  x0[mppi::SingleTrack::kOmegaFront] = x0[mppi::SingleTrack::kOmegaRear] = 5.f / 0.0975f;
  const int padded = b.shape().padded_samples;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<float> controls(static_cast<std::size_t>(kHorizon) * 2 * padded);
  for (float& v : controls) v = u(rng);
  std::vector<float> costs(static_cast<std::size_t>(padded));
  b.rollout(x0, controls, costs);
  costs.resize(kSamples);
  return costs;
}

double worst_relative(const std::vector<float>& a, const std::vector<float>& b) {
  double w = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    w = std::max(w, std::abs(double(a[i]) - b[i]) / std::max(1.0, std::abs(double(b[i]))));
  return w;
}

}  // namespace

TEST_CASE("Vulkan cost update: parameters and map change as on the CPU", "[vulkan][update]") {
  const int device = mppi::test::vulkan_test_device();
  if (device < 0) return;
  const mppi::SingleTrack model;
  const mppi::AutoRallyCost original(gazebo_map());
  mppi::vulkan::VulkanBackend gpu(*mppi::vulkan::twin_of(model, nullptr), original, kSamples, kHorizon, 0.02f, device);
  const std::vector<float> before = costs_of(gpu);

  std::string why;
  REQUIRE(gpu.set_cost_param("target_speed_mps", 9.0, &why));
  REQUIRE(gpu.set_cost_param("crash_discount", 0.8, &why));
  mppi::AutoRallyCostParams p;
  p.target_speed_mps = 9.f;
  p.crash_discount = 0.8f;
  mppi::CpuBackend<mppi::SingleTrack, mppi::AutoRallyCost> cpu(model, mppi::AutoRallyCost(gazebo_map(), p), kSamples,
                                                               kHorizon, 0.02f, 1);
  const std::vector<float> after = costs_of(gpu);
  CHECK(worst_relative(after, costs_of(cpu)) < 1e-3);
  CHECK(worst_relative(after, before) > 1e-2);  // the change is visible

  const mppi::CostMap& m = *gazebo_map();
  const auto shifted = std::make_shared<const mppi::CostMap>(m.x_min_m() + 1.f, m.x_max_m() + 1.f, m.y_min_m(),
                                                             m.y_max_m(), m.pixels_per_meter(), m.values());
  REQUIRE(gpu.set_cost_map(shifted, &why));
  REQUIRE(cpu.set_cost_map(shifted, &why));
  CHECK(worst_relative(costs_of(gpu), costs_of(cpu)) < 1e-3);

  const auto small = std::make_shared<const mppi::CostMap>(0.f, 1.f, 0.f, 1.f, 10.f, std::vector<float>(100, 0.f));
  const std::vector<float> kept = costs_of(gpu);
  CHECK_FALSE(gpu.set_cost_map(small, &why));
  CHECK_THAT(why, Catch::Contains("size"));
  CHECK(costs_of(gpu) == kept);
}
