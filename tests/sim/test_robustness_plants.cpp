// The robustness benchmark's mismatch plants (data/config/robustness/, docs/ROBUSTNESS.md):
// each is the default single-track car with exactly its one effect, and the effect does what
// the file says; and the limit lap's car of a corrected-model plant (plant_vehicle_params,
// sim/corrected_limit_vehicle.hpp).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "dynamics/corrected_model.hpp"
#include "dynamics/pacejka.hpp"
#include "dynamics/vehicle_params.hpp"
#include "dynamics/with_effects.hpp"
#include "sim/closed_loop.hpp"
#include "sim/corrected_limit_vehicle.hpp"
#include "sim/plant.hpp"

using namespace mppi;

namespace {

std::string config_file(const std::string& name) { return std::string(MPPI_TEST_DATA_DIR) + "/config/" + name; }

CorrectedModelFile robustness_plant(const std::string& name) {
  return load_corrected_model(config_file("robustness/" + name + ".yaml"));
}

// The EffectParams members of `e` that differ from their "off" values.
std::set<std::string> effects_set(const EffectParams& e) {
  const EffectParams off;
  std::set<std::string> set;
  for (const EffectSpec& spec : effect_table())
    for (const EffectParamSpec& p : spec.params)
      if (e.*(p.member) != off.*(p.member)) set.insert(p.name);
  return set;
}

void check_same_car(const SingleTrackParams& a, const SingleTrackParams& b) {
  CHECK(a.mass_kg == b.mass_kg);
  CHECK(a.yaw_inertia_kgm2 == b.yaw_inertia_kgm2);
  CHECK(a.tyre.B == b.tyre.B);
  CHECK(a.tyre.D == b.tyre.D);
  CHECK(a.tyre.Sv == b.tyre.Sv);
  CHECK(a.max_steer_rad == b.max_steer_rad);
  CHECK(a.stall_torque_Nm == b.stall_torque_Nm);
}

// A plant of the file as mppi-sim builds it: the pure delays on the actuators (instant slews).
sim::Plant<CorrectedSingleTrack> plant_of(const CorrectedModelFile& file) {
  sim::ActuatorLimits actuators;
  actuators.steer_rate_per_s = actuators.throttle_rate_per_s = 1e6f;
  actuators.steer_delay_s = static_cast<float>(file.effects.steer_delay_s);
  actuators.throttle_delay_s = static_cast<float>(file.effects.throttle_delay_s);
  EffectParams model_effects = file.effects;
  model_effects.steer_delay_s = model_effects.throttle_delay_s = 0.0;
  sim::Plant<CorrectedSingleTrack> plant(CorrectedSingleTrack(SingleTrack(file.nominal), model_effects), actuators,
                                         0.002f);
  plant.reset(VehicleState{});
  return plant;
}

const CorrectedModelFile& no_mismatch() {
  static const CorrectedModelFile file = [] {
    CorrectedModelFile f;
    f.nominal = load_single_track_params(config_file("autorally_single_track.yaml"));
    return f;
  }();
  return file;
}

}  // namespace

TEST_CASE("robustness plants: the default single-track car with exactly one effect each", "[sim][robustness]") {
  const SingleTrackParams nominal = no_mismatch().nominal;
  const std::pair<const char*, std::set<std::string>> plants[] = {
      {"delay", {"steer_delay_s", "throttle_delay_s"}},
      {"grip", {"grip_scale"}},  // grip_change_time_s = 0, its "off" value: from the start
      {"grade", {"grade_x"}},
      {"payload", {"mass_scale", "yaw_inertia_scale"}},
  };
  for (const auto& [name, effects] : plants) {
    INFO(name);
    const CorrectedModelFile file = robustness_plant(name);
    CHECK(file.nominal_model == "single-track");
    check_same_car(file.nominal, nominal);
    CHECK(effects_set(file.effects) == effects);
  }
  CHECK(robustness_plant("delay").effects.steer_delay_s == 0.08);
  CHECK(robustness_plant("delay").effects.throttle_delay_s == 0.08);
  CHECK(robustness_plant("grip").effects.grip_change_time_s == 0.0);
  CHECK(robustness_plant("grade").effects.grade_x == 0.06);
  CHECK(robustness_plant("payload").effects.mass_scale == 1.25);
}

TEST_CASE("robustness plants: grip x 0.7 scales the whole friction curve, its peak included", "[sim][robustness]") {
  const CorrectedModelFile file = robustness_plant("grip");
  // The tyres after the grip change, as WithEffects builds them (the change is at t = 0).
  const SingleTrackParams low = apply_effect_params(file.nominal, file.effects, file.effects.grip_scale);
  const auto nominal = PacejkaCoeffs<double>::from(file.nominal.tyre);
  const auto scaled = PacejkaCoeffs<double>::from(low.tyre);
  double peak_nominal = 0.0, peak_scaled = 0.0;
  for (double slip = 0.0; slip <= 3.0; slip += 0.001) {
    const double mu = magic_formula_mu(slip, nominal), mu_low = magic_formula_mu(slip, scaled);
    CHECK(mu_low == Approx(0.7 * mu).margin(1e-12));
    peak_nominal = std::max(peak_nominal, std::abs(mu));
    peak_scaled = std::max(peak_scaled, std::abs(mu_low));
  }
  CHECK(peak_scaled == Approx(0.7 * peak_nominal).epsilon(1e-9));
}

TEST_CASE("robustness plants: a car sliding sideways is stopped by 0.7x the nominal force", "[sim][robustness]") {
  // At 5 m/s with 1 m/s of sideways slide and no yaw rate, both axles slide: the lateral
  // deceleration over the first 2 ms is the friction force over the mass.
  auto lateral_decel_mps2 = [](const CorrectedModelFile& file) {
    sim::Plant<CorrectedSingleTrack> plant = plant_of(file);
    VehicleState s;
    s.vx_mps = 5.f;
    s.vy_mps = 1.f;
    plant.reset(s);
    plant.advance({0.f, 0.f}, 0.002f);
    return (1.0 - plant.vehicle_state().vy_mps) / 0.002;
  };
  const double nominal = lateral_decel_mps2(no_mismatch()), low = lateral_decel_mps2(robustness_plant("grip"));
  INFO("lateral deceleration: nominal " << nominal << " m/s^2, grip " << low << " m/s^2");
  CHECK(nominal > 1.0);
  CHECK(low / nominal == Approx(0.7).margin(0.02));
}

TEST_CASE("robustness plants: the delay holds both commands back 0.08 s", "[sim][robustness]") {
  sim::Plant<CorrectedSingleTrack> plant = plant_of(robustness_plant("delay"));
  for (int i = 0; i < 60; ++i) {  // a step command at t = 0, read every 2 ms for 0.12 s
    plant.advance({0.5f, 0.4f}, 0.002f);
    const double t_s = (i + 1) * 0.002;
    INFO("t = " << t_s << " s");
    CHECK(plant.applied().steer == Approx(t_s > 0.08 + 1e-6 ? 0.5 : 0.0));
    CHECK(plant.applied().throttle == Approx(t_s > 0.08 + 1e-6 ? 0.4 : 0.0));
  }
}

TEST_CASE("robustness plants: on the 6 % grade a car at rest rolls back downhill along x only", "[sim][robustness]") {
  const CorrectedModelFile file = robustness_plant("grade");
  auto rolls = [&](float yaw_rad) {
    sim::Plant<CorrectedSingleTrack> plant = plant_of(file);
    VehicleState s;
    s.yaw_rad = yaw_rad;
    plant.reset(s);
    plant.advance({0.f, 0.f}, 0.2f);
    return plant.vehicle_state();
  };
  // Facing uphill (+x): the slope pulls back with g 0.06 = 0.59 m/s^2, less what the rotating
  // wheels and the motor's back-EMF take.
  const double vx_mps = rolls(0.f).vx_mps;
  CHECK(vx_mps < -0.4 * 9.81 * 0.06 * 0.2);
  CHECK(vx_mps > -1.01 * 9.81 * 0.06 * 0.2);
  // Facing across the slope (+y): no pull along the car.
  CHECK(std::abs(rolls(static_cast<float>(M_PI / 2)).vx_mps) < 1e-3);
  sim::Plant<CorrectedSingleTrack> flat = plant_of(no_mismatch());
  flat.advance({0.f, 0.f}, 0.2f);
  CHECK(std::abs(flat.vehicle_state().vx_mps) < 1e-3);
}

TEST_CASE("robustness plants: the 25 % payload slows the car's acceleration", "[sim][robustness]") {
  auto speed_after_s = [](const CorrectedModelFile& file, float seconds) {
    sim::Plant<CorrectedSingleTrack> plant = plant_of(file);
    plant.advance({0.f, 0.3f}, seconds);
    return static_cast<double>(plant.vehicle_state().vx_mps);
  };
  const double nominal = speed_after_s(no_mismatch(), 0.5f), loaded = speed_after_s(robustness_plant("payload"), 0.5f);
  INFO("speed after 0.5 s: nominal " << nominal << " m/s, payload " << loaded << " m/s");
  // The wheels' inertia is not part of the payload: the ratio lies between 1 / 1.25 and 1.
  CHECK(nominal > 0.5);
  CHECK(loaded / nominal > 1.0 / 1.25);
  CHECK(loaded / nominal < 0.95);
}

TEST_CASE("limit lap car of a corrected plant: payload and grip from the start count, grade and delays do not",
          "[sim][robustness][limit_lap]") {
  const SingleTrackParams nominal = no_mismatch().nominal;
  auto vehicle_of = [](const std::string& file) {
    sim::ClosedLoopConfig config;
    config.plant = "corrected";
    config.plant_params_yaml = file;
    const std::optional<SingleTrackParams> vehicle = sim::plant_vehicle_params(config);
    REQUIRE(vehicle);
    return *vehicle;
  };
  check_same_car(vehicle_of(config_file("robustness/delay.yaml")), nominal);
  check_same_car(vehicle_of(config_file("robustness/grade.yaml")), nominal);
  // The actuated plant's effects are all actuator effects: its own nominal car.
  check_same_car(vehicle_of(config_file("autorally_single_track_actuated.yaml")),
                 load_corrected_model(config_file("autorally_single_track_actuated.yaml")).nominal);

  const SingleTrackParams grip = vehicle_of(config_file("robustness/grip.yaml"));
  CHECK(grip.tyre.D == Approx(0.7 * nominal.tyre.D));
  CHECK(grip.tyre.Sv == Approx(0.7 * nominal.tyre.Sv));
  CHECK(grip.tyre.B == nominal.tyre.B);
  CHECK(grip.mass_kg == nominal.mass_kg);

  const SingleTrackParams payload = vehicle_of(config_file("robustness/payload.yaml"));
  CHECK(payload.mass_kg == Approx(1.25 * nominal.mass_kg));
  CHECK(payload.yaw_inertia_kgm2 == Approx(1.25 * nominal.yaw_inertia_kgm2));
  CHECK(payload.tyre.D == nominal.tyre.D);

  // A grip change later in the run is not the car's: the reference keeps the nominal tyres.
  CorrectedModelFile later = robustness_plant("grip");
  later.effects.grip_change_time_s = 5.0;
  CHECK(sim::corrected_limit_lap_vehicle(later)->tyre.D == nominal.tyre.D);
  // Another nominal model: no reference.
  CorrectedModelFile network = later;
  network.nominal_model = "autorally-nn";
  CHECK_FALSE(sim::corrected_limit_lap_vehicle(network));
}
