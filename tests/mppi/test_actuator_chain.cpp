// Actuator-aware planning (mppi/actuator_chain.hpp): the chain against a plain scalar
// simulation of a delay, a rate limit and a lag written in the test; and in closed loop, a
// controller that knows a pure delay drives the delayed plant as the undelayed controller
// drives the undelayed plant (shifted by the delay), where the controller that ignores the delay
// does not.
#include <catch2/catch.hpp>

#include <cmath>
#include <deque>
#include <random>
#include <vector>

#include "mppi/actuator_chain.hpp"
#include "mppi/controller.hpp"
#include "tests/mppi/linear_system.hpp"

using mppi::test::DoubleIntegrator;
using mppi::test::QuadraticCost;

namespace {
// The oracle: a servo behind a slewing driver behind a transport delay, one channel, stepped
// at dt with the command held over the step.
struct ReferenceActuator {
  std::deque<double> in_flight;  // oldest first
  double slewed = 0, out = 0;
  int delay_steps;
  double max_change, alpha;
  ReferenceActuator(int d, double rate_per_s, double lag_s, double dt)
      : in_flight(static_cast<std::size_t>(d), 0.0), delay_steps(d),
        max_change(rate_per_s > 0 ? rate_per_s * dt : 1e30), alpha(lag_s > 0 ? 1 - std::exp(-dt / lag_s) : 1) {}
  double step(double command) {
    in_flight.push_back(command);
    const double acting = in_flight.front();
    in_flight.pop_front();
    slewed += std::clamp(acting - slewed, -max_change, max_change);
    out += alpha * (slewed - out);
    return out;
  }
};
}  // namespace

TEST_CASE("the actuator chain equals a scalar delay, rate limit and lag", "[core][mppi][actuators]") {
  const float dt = 0.02f;
  const mppi::ActuatorChannel ch{0.1f, 0.08f, 4.f};
  const mppi::ActuatorStep st = mppi::actuator_step(ch, dt);
  REQUIRE(st.delay_steps == 5);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> cmd(-1.f, 1.f);
  // The carried state after 17 random commands, then a rollout of 40 more in 16 lanes (lane j
  // gets the commands scaled by j / 15): each lane's inputs equal the reference continued with
  // that lane's commands.
  ReferenceActuator carried(5, 4.0, 0.08, dt);
  mppi::ActuatorState state;
  for (int i = 0; i < 17; ++i) {
    const float c = cmd(rng);
    mppi::advance_actuators(&st, 1, &c, state);
    CHECK(state.lag_out[0] == Approx(carried.step(c)).margin(1e-5));
  }
  constexpr int W = 16, T = 40;
  std::vector<float> v(T * W);
  std::vector<float> base(T);
  for (float& b : base) b = cmd(rng);
  for (int t = 0; t < T; ++t)
    for (int j = 0; j < W; ++j) v[t * W + j] = base[t] * static_cast<float>(j) / 15.f;
  const mppi::ActuatorPlan plan{&st, &state};
  float rate[W], lag[W], u[W];
  std::vector<ReferenceActuator> lanes(W, carried);
  double worst = 0;
  for (int t = 0; t < T; ++t) {
    mppi::detail::actuator_inputs<W>(plan, 1, t, v.data(), W, W, rate, lag, u);
    for (int j = 0; j < W; ++j) worst = std::max(worst, std::abs(u[j] - lanes[j].step(v[t * W + j])));
  }
  CHECK(worst < 1e-5);
}

TEST_CASE("planning through a known pure delay drives the delayed plant as the undelayed loop",
          "[core][mppi][actuators]") {
  // Regulate a double integrator from p = 1 with the acceleration acting 6 steps (0.3 s) late.
  const int delay = 6, steps = 80;
  const float dt = 0.05f;
  mppi::ControllerOptions o;
  o.num_samples = 1024;
  o.horizon = 40;
  o.dt_s = dt;
  o.iterations = 3;
  o.lambda = 0.05f;
  o.noise_std = {1.5f};
  o.control_min = {-8.f};
  o.control_max = {8.f};
  o.safe_control = {0.f};
  o.seed = 4;
  const QuadraticCost cost{1.f, 0.2f, 0.01f};

  // The closed loop: plant and controller; the plant's input is the command `plant_delay`
  // steps old (zeros before the first).
  auto run = [&](int plant_delay, bool controller_knows) {
    auto opts = o;
    if (controller_knows) opts.actuators = {{plant_delay * dt, 0.f, 0.f}};
    auto c = mppi::make_cpu_controller(DoubleIntegrator{}, cost, opts);
    std::deque<float> in_flight(static_cast<std::size_t>(plant_delay), 0.f);
    float x[2] = {1.f, 0.f};
    std::vector<float> position;
    for (int i = 0; i < steps; ++i) {
      position.push_back(x[0]);
      mppi::StepSummary s;
      const float u = c.step(x, &s)[0];
      REQUIRE(s.status == mppi::StepStatus::kOk);
      in_flight.push_back(u);
      const float acting = in_flight.front();
      in_flight.pop_front();
      x[0] += dt * x[1];
      x[1] += dt * acting;
    }
    return position;
  };
  const auto undelayed = run(0, false);
  const auto compensated = run(delay, true);
  const auto ignorant = run(delay, false);
  // The compensated loop is the undelayed one shifted by the delay: it cannot act before then.
  double err_comp = 0, err_ignorant = 0;
  for (int i = 0; i + delay < steps; ++i) {
    err_comp = std::max(err_comp, std::abs(static_cast<double>(compensated[i + delay]) - undelayed[i]));
    err_ignorant = std::max(err_ignorant, std::abs(static_cast<double>(ignorant[i + delay]) - undelayed[i]));
  }
  INFO("max deviation from the shifted undelayed loop: compensated " << err_comp << ", ignoring the delay "
                                                                       << err_ignorant);
  CHECK(err_comp < 0.1);
  CHECK(err_ignorant > 3 * err_comp);
  // Both settle where the undelayed loop does, the ignorant one only with overshoot.
  CHECK(std::abs(compensated.back()) < 0.05);
}

TEST_CASE("actuator settings are checked, and a reset puts the actuators at rest", "[core][mppi][actuators]") {
  mppi::ControllerOptions o;
  o.num_samples = 64;
  o.horizon = 10;
  o.noise_std = {1.f};
  o.control_min = {-1.f};
  o.control_max = {1.f};
  o.safe_control = {0.f};
  std::string why;
  o.actuators = {{0.f, 0.f, 0.f}, {0.f, 0.f, 0.f}};
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("one per control channel") != std::string::npos);
  o.actuators = {{-0.1f, 0.f, 0.f}};
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("delay_s") != std::string::npos);
  o.actuators = {{5.f, 0.f, 0.f}};  // 250 steps of 0.02 s: more than the chain carries
  CHECK_FALSE(o.is_valid(1, &why));
  o.actuators = {{0.f, std::nanf(""), 0.f}};
  CHECK_FALSE(o.is_valid(1, &why));
  CHECK(why.find("lag_s") != std::string::npos);
  o.actuators = {{0.04f, 0.1f, 3.f}};
  CHECK(o.is_valid(1, &why));
  // The CPU backend rolls out through the actuators; a reset puts them at rest.
  auto c = mppi::make_cpu_controller(DoubleIntegrator{}, QuadraticCost{}, o);
  const float x0[2] = {1.f, 0.f};
  c.step(x0);
  c.step(x0);
  CHECK(c.actuator_state().pending[0][1] != 0.f);
  c.reset();
  CHECK(c.actuator_state().pending[0][1] == 0.f);
  CHECK(c.actuator_state().lag_out[0] == 0.f);
}
