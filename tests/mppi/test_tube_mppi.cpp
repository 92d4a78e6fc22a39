// The tube and robust variants (ControllerOptions::variant): the control sent is the plan's
// first control plus the published gains times the measured state's distance from the nominal
// one; the nominal state follows the model and is put back on the measured state by each
// variant's rule; under a disturbance the model does not know, the feedback holds the car
// closer to its plan than the plain controller does.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "mppi/controller.hpp"
#include "tests/mppi/linear_system.hpp"

using mppi::test::DoubleIntegrator;
using mppi::test::QuadraticCost;

namespace {
mppi::ControllerOptions tube_options(mppi::ControllerVariant variant) {
  mppi::ControllerOptions o;
  o.num_samples = 512;
  o.horizon = 30;
  o.dt_s = 0.05f;
  o.iterations = 2;
  o.lambda = 0.05f;
  o.noise_std = {1.f};
  o.control_min = {-20.f};
  o.control_max = {20.f};
  o.safe_control = {0.f};
  o.seed = 9;
  o.variant = variant;
  o.ancillary.q_diag = {4.f, 1.f};
  o.ancillary.r_diag = {0.1f};
  o.tube_reset_distance = 10.f;
  return o;
}
}  // namespace

TEST_CASE("tube MPPI sends the plan's control plus the published gains times the state error",
          "[core][mppi][tube]") {
  auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, tube_options(mppi::ControllerVariant::kTube));
  float x[2] = {1.f, 0.f};
  mppi::StepSummary s;
  c.step(x, &s);  // first step: the nominal state starts at the measured one
  REQUIRE(s.feedback_applied);
  CHECK(s.nominal_reset);
  CHECK(c.nominal_states().size() == 31 * 2);
  CHECK(c.feedback_gains().size() == 30 * 2);
  // The nominal state moved on under the plan's first control: its model prediction.
  const std::vector<float> predicted(c.nominal_state().begin(), c.nominal_state().end());
  // A measured state off the prediction by (0.2, -0.1).
  float measured[2] = {predicted[0] + 0.2f, predicted[1] - 0.1f};
  const auto u = c.step(measured, &s);
  REQUIRE(s.status == mppi::StepStatus::kOk);
  CHECK_FALSE(s.nominal_reset);
  CHECK(s.tube_distance == Approx(std::sqrt(4 * 0.04 + 0.01)).epsilon(1e-4));
  // The plan was made from the predicted state: nominal_states()[0] is it.
  CHECK(c.nominal_states()[0] == Approx(predicted[0]).margin(1e-6));
  // u = u_nom_0 + K_0 (x - x_nom); u_nom_0 is the first row of the plan before its shift,
  // nominal_states()[1] is where it takes the nominal state.
  const auto k0 = c.feedback_gains();
  const float u_nom = [&] {
    // the shifted plan lost u_nom_0; recover it from the nominal states: v1 = v0 + dt u
    return (c.nominal_states()[3] - c.nominal_states()[1]) / 0.05f;
  }();
  CHECK(u[0] == Approx(u_nom + k0[0] * 0.2f + k0[1] * -0.1f).margin(2e-3));
  CHECK(k0[0] < 0.f);  // pushes back towards the nominal position
  CHECK(k0[1] < 0.f);
}

TEST_CASE("tube MPPI puts the nominal state back on the measured one beyond the reset distance",
          "[core][mppi][tube]") {
  auto o = tube_options(mppi::ControllerVariant::kTube);
  o.tube_reset_distance = 0.5f;
  auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, o);
  float x[2] = {1.f, 0.f};
  mppi::StepSummary s;
  c.step(x, &s);
  float near[2] = {c.nominal_state()[0] + 0.1f, c.nominal_state()[1]};
  c.step(near, &s);
  CHECK_FALSE(s.nominal_reset);
  float far[2] = {c.nominal_state()[0] + 0.3f, c.nominal_state()[1]};  // sqrt(4 * 0.09) = 0.6 > 0.5
  c.step(far, &s);
  CHECK(s.nominal_reset);
  CHECK(c.nominal_states()[0] == Approx(far[0]).margin(1e-6));
  c.reset();
  c.step(x, &s);
  CHECK(s.nominal_reset);  // a reset starts the nominal state again
}

TEST_CASE("robust MPPI takes the measured state when the plan costs no more from it", "[core][mppi][tube]") {
  auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{},
                                     tube_options(mppi::ControllerVariant::kRobust));
  float x[2] = {1.f, 0.f};
  mppi::StepSummary s;
  c.step(x, &s);
  // Closer to the goal (0, 0) than the nominal state: the plan costs less from it -> reset.
  float better[2] = {c.nominal_state()[0] * 0.5f, c.nominal_state()[1]};
  c.step(better, &s);
  CHECK(s.nominal_reset);
  // Farther from the goal: the plan costs more -> the nominal state is kept.
  float worse[2] = {c.nominal_state()[0] + 0.5f, c.nominal_state()[1] + 0.3f};
  c.step(worse, &s);
  CHECK_FALSE(s.nominal_reset);
  CHECK(s.feedback_applied);
}

TEST_CASE("under an unknown push the tube's feedback keeps the state nearer its plan", "[core][mppi][tube]") {
  // The plant is pushed by a constant 3 m/s^2 the model does not know. Both controllers
  // regulate p to 0; the tube variant's feedback acts on the measured error at once.
  auto run = [](mppi::ControllerVariant variant) {
    auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, tube_options(variant));
    float x[2] = {1.f, 0.f};
    double sum_sq = 0;
    for (int i = 0; i < 80; ++i) {
      mppi::StepSummary s;
      const float u = c.step(x, &s)[0];
      REQUIRE(s.status == mppi::StepStatus::kOk);
      x[0] += 0.05f * x[1];
      x[1] += 0.05f * (u + 3.f);
      if (i >= 40) sum_sq += static_cast<double>(x[0]) * x[0];
    }
    return std::sqrt(sum_sq / 40);
  };
  const double plain = run(mppi::ControllerVariant::kPlain);
  const double tube = run(mppi::ControllerVariant::kTube);
  INFO("rms position over the last 2 s: plain " << plain << ", tube " << tube);
  CHECK(tube < 1.0);  // it still regulates
  CHECK(tube < 0.8 * plain);  // measured: 0.51 against 0.74
}

TEST_CASE("the variants refuse what they cannot do", "[core][mppi][tube]") {
  auto o = tube_options(mppi::ControllerVariant::kTube);
  std::string why;
  o.actuators = {{0.02f, 0.f, 0.f}};
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("actuator") != std::string::npos);
  o.actuators.clear();
  o.tube_reset_distance = 0.f;
  CHECK_FALSE(o.is_valid(1, &why));
  o.tube_reset_distance = 1.f;
  o.ancillary.q_diag = {1.f, 1.f, 1.f};  // the model has 2 states
  CHECK_THROWS_WITH(mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, o),
                    Catch::Contains("q_diag"));
  mppi::ControllerVariant v{};
  CHECK(mppi::parse_controller_variant("robust", &v));
  CHECK(v == mppi::ControllerVariant::kRobust);
  CHECK_FALSE(mppi::parse_controller_variant("rmppi", &v));
}
