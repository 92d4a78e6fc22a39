// Controller::step() against failing backends: the failure becomes a status, the safe control
// and the backend's message; with a fallback the controller goes on where it stopped. Oracle:
// a controller that never failed, fed the same states minus the failed step, gives the same
// controls bit for bit (the failed step changes neither the plan nor the noise counter).
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "mppi/controller.hpp"
#include "mppi/cpu_backend.hpp"
#include "tests/mppi/linear_system.hpp"

using mppi::test::DoubleIntegrator;
using mppi::test::QuadraticCost;

namespace {

mppi::ControllerOptions small_options() {
  mppi::ControllerOptions o;
  o.num_samples = 256;
  o.horizon = 15;
  o.dt_s = 0.1f;
  o.iterations = 1;
  o.lambda = 0.05f;
  o.gamma = 0.f;
  o.noise_std = {0.5f};
  o.control_min = {-5.f};
  o.control_max = {5.f};
  o.safe_control = {0.25f};
  o.seed = 5;
  o.num_threads = 1;
  return o;
}

std::unique_ptr<mppi::Backend> cpu_backend(const mppi::ControllerOptions& o) {
  return std::make_unique<mppi::CpuBackend<DoubleIntegrator, QuadraticCost>>(
      DoubleIntegrator{}, QuadraticCost{}, o.num_samples, o.horizon, o.dt_s, o.num_threads, o.schedule);
}

// Some plausible states of a car-like double integrator (position, velocity).
std::vector<float> state(int k) { return {1.f - 0.07f * static_cast<float>(k), 0.3f - 0.02f * static_cast<float>(k)}; }

}  // namespace

TEST_CASE("a lost device mid-run: safe control once, then the fallback continues the plan", "[core][mppi][fault]") {
  const auto o = small_options();
  mppi::Controller failing(cpu_backend(o), o);
  failing.set_fallback_backend([o] { return cpu_backend(o); });
  constexpr int kLostAt = 3;
  failing.inject_device_loss(kLostAt);
  mppi::Controller reference(cpu_backend(o), o);

  for (int k = 0; k < 10; ++k) {
    INFO("step " << k);
    const auto x = state(k);
    mppi::StepSummary s;
    const float u = failing.step(x, &s)[0];
    REQUIRE(std::isfinite(u));
    if (k == kLostAt) {
      CHECK(s.status == mppi::StepStatus::kBackendError);
      CHECK(s.backend_switched);
      CHECK(u == 0.25f);  // the safe control
      CHECK_THAT(std::string(s.reason), Catch::Contains("device lost"));
      continue;  // the reference never sees this state
    }
    CHECK(s.status == mppi::StepStatus::kOk);
    CHECK_FALSE(s.backend_switched);
    CHECK(u == reference.step(x)[0]);  // bit for bit: same plan, same noise counter
  }
  REQUIRE(failing.backend_switches().size() == 1);
  const auto& sw = failing.backend_switches()[0];
  CHECK(sw.step_call == kLostAt);
  CHECK(sw.from == "cpu");
  CHECK(sw.to == "cpu");
  CHECK_THAT(sw.reason, Catch::Contains("device lost"));
  CHECK_FALSE(failing.has_fallback_backend());  // used once
}

TEST_CASE("without a fallback a failed backend gives the safe control every step, never an exception", "[core][mppi][fault]") {
  auto o = small_options();
  o.iterations = 2;
  mppi::Controller c(cpu_backend(o), o);
  c.inject_device_loss(1);
  mppi::StepSummary s;
  CHECK(c.step(state(0), &s)[0] != 0.25f);
  CHECK(s.status == mppi::StepStatus::kOk);
  for (int k = 1; k < 5; ++k) {
    float u = 0.f;
    REQUIRE_NOTHROW(u = c.step(state(k), &s)[0]);
    CHECK(u == 0.25f);
    CHECK(s.status == mppi::StepStatus::kBackendError);
    CHECK_FALSE(s.backend_switched);
    CHECK_THAT(std::string(s.reason), Catch::StartsWith("cpu backend failed: ") && Catch::Contains("device lost"));
  }
  CHECK(c.backend_switches().empty());
  // A cost change on the failed backend is refused with a reason instead of throwing.
  std::string why;
  CHECK_FALSE(c.set_cost_param("target_speed_mps", 3.0, &why));
  CHECK_THAT(why, Catch::Contains("device lost"));
}

TEST_CASE("a fallback that cannot be built leaves the safe control and no switch", "[core][mppi][fault]") {
  const auto o = small_options();
  mppi::Controller c(cpu_backend(o), o);
  c.set_fallback_backend([]() -> std::unique_ptr<mppi::Backend> { throw mppi::Error("no CPU either"); });
  c.inject_device_loss(0);
  mppi::StepSummary s;
  CHECK(c.step(state(0), &s)[0] == 0.25f);
  CHECK(s.status == mppi::StepStatus::kBackendError);
  CHECK_FALSE(s.backend_switched);
  CHECK(c.backend_switches().empty());
}
