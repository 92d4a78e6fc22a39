// The online grip adaptation in the closed loop: the single-track model's lateral force fitted
// against a plant whose whole tyre curve is scaled by 0.7 (data/config/robustness/grip.yaml, the
// corrected-model effect friction_change, written apart from the adaptation) comes out near 0.7,
// and near 1 on the nominal plant; the cost's target speed follows the fit.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "mppi/controller.hpp"
#include "sim/closed_loop.hpp"
#include "test_data.hpp"

namespace {
// The controller's fitted scale and governed speed at every step.
class AdaptationWatch final : public mppi::sim::StepObserver {
 public:
  void on_start(mppi::sim::PathPredictor) override {}
  void after_step(const mppi::sim::StepView& v) override {
    scales.push_back(v.controller->lateral_force_scale());
    speeds.push_back(v.controller->governed_speed());
    requested.push_back(v.controller->requested_speed());
  }
  mppi::sim::OperatorRequests poll_requests(double) override { return {}; }
  std::vector<double> scales, speeds, requested;
};

double median_of_second_half(std::vector<double> v) {
  v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

mppi::sim::RunSummary adapted_run(const std::string& plant, const std::string& plant_file, AdaptationWatch* watch) {
  mppi::sim::ClosedLoopConfig c;
  c.track = "gazebo";
  c.model = "single-track";
  c.plant = plant;
  c.plant_params_yaml = plant_file;
  c.target_speed_mps = 6.0;
  c.laps = 1;
  c.controller.num_samples = 384;
  c.controller.horizon = 60;
  c.controller.seed = 2;
  c.controller.force_adaptation.enabled = true;
  c.progress = false;
  c.observer = watch;
  return mppi::sim::run_closed_loop(c);
}
}  // namespace

TEST_CASE("grip adaptation finds the plant's grip and slows the target speed with it", "[sim][adaptation]") {
  AdaptationWatch low, nominal;
  const auto low_run =
      adapted_run("corrected", mppi::test::data_path("config/robustness/grip.yaml"), &low);
  const auto nominal_run = adapted_run("single-track", "", &nominal);
  const double low_scale = median_of_second_half(low.scales);
  const double nominal_scale = median_of_second_half(nominal.scales);
  INFO("fitted scale: grip x 0.7 plant " << low_scale << ", nominal plant " << nominal_scale);
  CHECK(low_scale == Approx(0.7).margin(0.08));
  CHECK(nominal_scale == Approx(1.0).margin(0.08));
  CHECK(low_run.lateral_force_adaptation);
  CHECK(low_run.lateral_force_scale_p50 == Approx(low_scale).margin(0.1));
  // The cost's target speed: the requested 6 m/s x the scale (exponent 1), resent past 0.5 %.
  for (std::size_t i = 0; i < low.scales.size(); ++i) {
    INFO("step " << i);
    REQUIRE(low.requested[i] == 6.0);
    REQUIRE(std::abs(low.speeds[i] - 6.0 * low.scales[i]) <= 0.005 * 6.0 + 1e-9);
  }
  CHECK(low_run.laps_completed == 1);
  CHECK(nominal_run.laps_completed == 1);
}
