// The simulated car's pure command delays: the actuator acts on the command given exactly that
// long before (closed form: a step command appears delay seconds later), and no delay leaves the
// plant as it was.
#include <catch2/catch.hpp>

#include "base/error.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "sim/plant.hpp"

using namespace mppi;

namespace {

sim::ActuatorLimits instant_actuators(float steer_delay_s, float throttle_delay_s) {
  sim::ActuatorLimits a;
  a.steer_rate_per_s = a.throttle_rate_per_s = 1e6f;
  a.steer_delay_s = steer_delay_s;
  a.throttle_delay_s = throttle_delay_s;
  return a;
}

}  // namespace

TEST_CASE("a plant's pure delays apply each command exactly that long after it was given", "[sim][plant]") {
  sim::Plant<KinematicBicycle> plant(KinematicBicycle{}, instant_actuators(0.05f, 0.12f), 0.002f);
  plant.reset(VehicleState{});
  plant.advance({0.f, 0.f}, 0.1f);
  // A step at t = 0.1 s to steer 0.8, throttle 0.5, held; read every 2 ms.
  double t = 0.1;
  for (int i = 0; i < 150; ++i) {
    plant.advance({0.8f, 0.5f}, 0.002f);
    t += 0.002;
    const double since_step_s = t - 0.1;
    INFO("t = " << t << " s");
    // The first substep after the step is the command's; it acts delay / dt steps later.
    CHECK(plant.applied().steer == Approx(since_step_s > 0.05 + 1e-6 ? 0.8 : 0.0));
    CHECK(plant.applied().throttle == Approx(since_step_s > 0.12 + 1e-6 ? 0.5 : 0.0));
  }
}

TEST_CASE("a plant without delays applies the command at once, and a reset forgets the queue", "[sim][plant]") {
  sim::Plant<KinematicBicycle> plain(KinematicBicycle{}, instant_actuators(0.f, 0.f), 0.002f);
  plain.reset(VehicleState{});
  plain.advance({0.6f, -0.3f}, 0.002f);
  CHECK(plain.applied().steer == Approx(0.6));
  CHECK(plain.applied().throttle == Approx(-0.3));

  sim::Plant<KinematicBicycle> delayed(KinematicBicycle{}, instant_actuators(0.02f, 0.02f), 0.002f);
  delayed.reset(VehicleState{});
  delayed.advance({1.f, 1.f}, 0.1f);
  CHECK(delayed.applied().steer == Approx(1.0));
  delayed.reset(VehicleState{});
  delayed.advance({-1.f, -1.f}, 0.002f);
  CHECK(delayed.applied().steer == Approx(0.0));  // the old commands are gone: at rest
  CHECK_THROWS_AS(sim::Plant<KinematicBicycle>(KinematicBicycle{}, instant_actuators(-0.1f, 0.f)), Error);
}
