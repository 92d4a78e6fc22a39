// Controller::step() allocates nothing for every registered model with the AutoRally cost, for
// a model with effects around it, and on the Vulkan backend (lavapipe here). The counter is the
// test program's counting operator new (tests/mppi/allocation_counter.hpp); each case first
// shows that the counter sees an allocation.
#include <catch2/catch.hpp>

#include <memory>
#include <string>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/with_effects.hpp"
#include "factory/make_controller.hpp"
#include "mppi/cost_map.hpp"
#include "test_data.hpp"
#include "tests/mppi/allocation_counter.hpp"

namespace {

mppi::AutoRallyCost gazebo_cost() {
  static const auto map = std::make_shared<const mppi::CostMap>(
      mppi::CostMap::load_npz(mppi::test::data_path("autorally/maps/gazebo/gazebo_costmap.npz")));
  return mppi::AutoRallyCost(map);
}

mppi::ControllerOptions small_options() {
  mppi::ControllerOptions o;
  o.num_samples = 256;
  o.horizon = 30;
  o.iterations = 2;
  o.smoothing_window = 5;
  o.num_threads = 2;
  return o;
}

// Allocations of 5 steps after a warm-up step, from a moving start on the Gazebo track.
template <class M>
long step_allocations(mppi::Controller& controller, const M& model) {
  mppi::VehicleState s;
  s.x_m = -8.5f;
  s.y_m = -8.9f;
  s.yaw_rad = 2.3561945f;
  s.vx_mps = 5.f;
  std::vector<float> x0(M::kNx, 0.f);
  model.init_state(s, x0.data());
  mppi::StepSummary summary;
  controller.step(x0, &summary);  // warm-up: thread pools, first-use buffers
  REQUIRE(summary.status == mppi::StepStatus::kOk);
  return mppi::test::allocations_in([&] {
    for (int i = 0; i < 5; ++i) controller.step(x0, &summary);
  });
}

std::string default_data(const char* file) {
  return std::string(file).empty() ? std::string() : mppi::test::data_path(file);
}

}  // namespace

TEST_CASE("step() allocates nothing for every registered model", "[core][mppi][alloc]") {
  CHECK(mppi::test::allocations_in([] { std::vector<float> v(10); }) >= 1);  // the counter works
  mppi::for_each_type(mppi::RegisteredModels{}, [&]<class D>() {
    INFO("model " << D::kName);
    const auto model = D::load(default_data(D::kDefaultFile));
    auto controller = mppi::make_cpu_controller(model, gazebo_cost(), small_options());
    CHECK(step_allocations(controller, model) == 0);
  });
}

TEST_CASE("step() allocates nothing for a model with effects", "[core][mppi][alloc]") {
  mppi::EffectParams e;
  e.steer_delay_s = 0.05;
  e.grip_scale = 0.8;
  e.grip_change_time_s = 0.3;  // lanes on both sides of the change within the horizon
  e.aero_drag_kgpm = 0.4;
  const mppi::CorrectedSingleTrack model(mppi::SingleTrack(), e);
  auto controller = mppi::make_cpu_controller(model, gazebo_cost(), small_options());
  CHECK(step_allocations(controller, model) == 0);
}

TEST_CASE("step() allocates nothing with the grip adaptation scaling the network and the speed",
          "[core][mppi][alloc][adaptation]") {
  const auto model = mppi::models::AutoRallyNetworkModel::load(default_data(mppi::models::AutoRallyNetworkModel::kDefaultFile));
  mppi::ControllerOptions o = small_options();
  o.force_adaptation.enabled = true;
  o.force_adaptation.scale_model = true;
  auto controller = mppi::make_cpu_controller(model, gazebo_cost(), o);
  REQUIRE(controller.set_cost_param("target_speed_mps", 8.0));
  // The same start state each step: the car "did not move" as the model said, so the fitted
  // scale moves and the model and the target speed change with it.
  CHECK(step_allocations(controller, model) == 0);
  CHECK(controller.lateral_force_scale() != 1.f);
  CHECK(controller.governed_speed() == Approx(8.0 * controller.lateral_force_scale()).epsilon(0.01));
}

TEST_CASE("step() allocates nothing on the Vulkan backend", "[core][mppi][alloc][vulkan]") {
  const mppi::SingleTrack model;
  mppi::BackendReport report;
  auto controller = mppi::make_controller(model, gazebo_cost(), small_options(), mppi::BackendChoice::kVulkan, &report);
  INFO("backend " << report.backend << ": " << report.reason);
  if (report.backend != "vulkan") {
    WARN("no Vulkan device: " << report.reason);
    return;
  }
  CHECK(step_allocations(controller, model) == 0);
}
