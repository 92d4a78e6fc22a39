// Calibration by open-loop prediction error (sysid/calibration.hpp) and the scripted
// manoeuvres (sysid/manoeuvre_rollout.hpp): the fit recovers known parameters from data made
// by the plant with those parameters, and the shipped calibrated plant predicts the AutoRally
// network better than the uncalibrated one.
#include <algorithm>
#include <cmath>
#include <set>

#include <catch2/catch.hpp>

#include "dynamics/autorally_nn.hpp"
#include "dynamics/vehicle_params.hpp"
#include "error_of.hpp"
#include "sysid/calibration.hpp"
#include "sysid/manoeuvre_rollout.hpp"
#include "sysid/vehicle_estimation.hpp"
#include "test_data.hpp"

namespace {

using namespace mppi;
using namespace mppi::sysid;
using mppi::test::error_of;

RolloutStep plant_step(const VehicleModelSpec& spec) {
  return [&spec](std::vector<double>& x, const double u[2], double dt) { spec.step(spec.nominal, x.data(), u, dt); };
}

RolloutStep network_step(const AutoRallyNetwork& net) {
  return [&net](std::vector<double>& x, const double u[2], double dt) {
    double dx[AutoRallyNetwork::kNx];
    net.derivatives(x.data(), u, dx);
    for (int i = 0; i < AutoRallyNetwork::kNx; ++i) x[static_cast<std::size_t>(i)] += dx[i] * dt;
  };
}

std::vector<double> wheels_rolling(const SingleTrackParams& p, double vx) {
  std::vector<double> x(9, 0.0);
  x[3] = vx;
  x[7] = x[8] = vx / p.wheel_radius_m;
  return x;
}

}  // namespace

TEST_CASE("the scripted manoeuvres cover the paper's speed range and all five manoeuvres", "[sysid][calibration]") {
  const AutoRallyNetwork net = AutoRallyNetwork::load(test::data_path("autorally/models/autorally_nnet_09_12_2018.npz"));
  ManoeuvreOptions o;
  o.duration_s = 60;
  const sim::Recording rec = roll_out_manoeuvres(network_step(net), std::vector<double>(7, 0.0), o);
  REQUIRE(rec.rows() == 3000);
  const auto& vx = rec.column("vx");
  const auto [lo, hi] = std::minmax_element(vx.begin() + 50, vx.end());
  CHECK(*lo > 2.5);
  CHECK(*lo < 4.5);
  CHECK(*hi > 8.5);
  CHECK(*hi < 11.5);
  const auto& seg = rec.column("segment");
  CHECK(std::set<double>(seg.begin(), seg.end()) == std::set<double>{1, 2, 3, 4, 5});
  const auto& thr = rec.column("throttle");
  CHECK(*std::max_element(thr.begin(), thr.end()) <= 0.65);
  CHECK(*std::min_element(thr.begin(), thr.end()) < -0.25);  // braking is excited
  const auto& steer = rec.column("steer");
  CHECK(*std::max_element(steer.begin(), steer.end()) > 0.7);  // near full lock (sliding)
  // A different seed gives a different sequence.
  o.seed = 2;
  const sim::Recording other = roll_out_manoeuvres(network_step(net), std::vector<double>(7, 0.0), o);
  CHECK(other.column("steer")[400] != rec.column("steer")[400]);
}

TEST_CASE("calibration recovers known drivetrain, brake, steering and tyre parameters", "[sysid][calibration]") {
  const std::vector<std::string> names = {"max_steer_rad", "stall_torque_Nm", "brake_torque_ratio",
                                          "rolling_resistance", "tyre.D"};
  SingleTrackParams truth;
  truth.max_steer_rad = 0.30;
  truth.stall_torque_Nm = 22.0;
  truth.brake_torque_ratio = 0.4;
  truth.rolling_resistance = 0.09;
  truth.tyre.D = 0.85;
  const VehicleModelSpec truth_spec = single_track_spec(truth, names);
  ManoeuvreOptions o;
  o.duration_s = 40;
  o.ff_offset = 0.04;  // the default plant's throttle line (about 20 m/s per unit throttle)
  o.ff_per_mps = 0.05;
  o.extra_state_columns = {"omega_front", "omega_rear"};
  const sim::Recording rec = roll_out_manoeuvres(plant_step(truth_spec), wheels_rolling(truth, 5.0), o);

  const VehicleModelSpec start = single_track_spec(SingleTrackParams{}, names);  // 0.38, 10, 1, 0.05, 0.9956
  const std::vector<double> scales = channel_scales(rec, {"vx", "vy", "yaw_rate"});
  CalibrationOptions c;
  c.max_iterations = 30;
  const CalibrationResult fit = calibrate(start, rec, scales, c);
  REQUIRE(fit.values.size() == names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    INFO(names[i] << ": fitted " << fit.values[i] << ", true " << truth_spec.nominal[i]);
    CHECK(fit.values[i] == Approx(truth_spec.nominal[i]).epsilon(0.03));
  }
  const PredictionError before = prediction_error(start, start.nominal, rec, scales);
  const PredictionError after = prediction_error(start, fit.values, rec, scales);
  CHECK(before.mean_nrmse > 0.1);
  CHECK(after.mean_nrmse < 0.01 * before.mean_nrmse);
  // The truth predicts its own data exactly (the same integrator from the recorded full state).
  CHECK(prediction_error(truth_spec, truth_spec.nominal, rec, scales).mean_nrmse < 1e-6);
}

TEST_CASE("the shipped calibrated single-track predicts the AutoRally network better than the uncalibrated one",
          "[sysid][calibration]") {
  const AutoRallyNetwork net = AutoRallyNetwork::load(test::data_path("autorally/models/autorally_nnet_09_12_2018.npz"));
  ManoeuvreOptions o;
  o.duration_s = 40;
  o.seed = 77;  // not a seed the shipped calibration was fitted on (1) or judged on (1001)
  const sim::Recording rec = roll_out_manoeuvres(network_step(net), std::vector<double>(7, 0.0), o);
  const std::vector<std::string> none;
  const VehicleModelSpec old_plant =
      single_track_spec(load_single_track_params(test::data_path("config/autorally_single_track_uncalibrated.yaml")), none);
  const VehicleModelSpec new_plant =
      single_track_spec(load_single_track_params(test::data_path("config/autorally_single_track.yaml")), none);
  const std::vector<double> scales = channel_scales(rec, {"vx", "vy", "yaw_rate"});
  PredictionErrorOptions one_step;
  one_step.horizon_s = 0.02;
  one_step.stride_s = 0.02;
  one_step.report_horizons_s = {0.02};
  const double old_one = prediction_error(old_plant, {}, rec, scales, one_step).mean_nrmse;
  const double new_one = prediction_error(new_plant, {}, rec, scales, one_step).mean_nrmse;
  CHECK(new_one < old_one);
  const double old_1s = prediction_error(old_plant, {}, rec, scales).mean_nrmse;
  const double new_1s = prediction_error(new_plant, {}, rec, scales).mean_nrmse;
  INFO("1-s NRMSE uncalibrated " << old_1s << ", calibrated " << new_1s);
  // Measured: 0.434 -> 0.305 (-30 %) on the held-out seed of the shipped fit; the lateral
  // channels limit it (docs/CALIBRATION.md). Guard the gain with a margin.
  CHECK(new_1s < 0.8 * old_1s);
}

TEST_CASE("prediction error and calibration reject bad input by name", "[sysid][calibration]") {
  const VehicleModelSpec spec = single_track_spec(SingleTrackParams{}, {"tyre.D"});
  ManoeuvreOptions o;
  o.duration_s = 5;
  const sim::Recording rec = roll_out_manoeuvres(plant_step(spec), wheels_rolling(SingleTrackParams{}, 5.0), o);
  PredictionErrorOptions bad;
  bad.channels = {"vx", "pitch_rate"};
  CHECK_THAT(error_of([&] { prediction_error(spec, spec.nominal, rec, {1.0, 1.0}, bad); }),
             Catch::Contains("pitch_rate"));
  CHECK_THAT(error_of([&] { channel_scales(rec, {"no_such_column"}); }), Catch::Contains("no_such_column"));
  PredictionErrorOptions too_long;
  too_long.horizon_s = 10.0;
  too_long.report_horizons_s = {1.0};
  CHECK_THAT(error_of([&] { prediction_error(spec, spec.nominal, rec, {1, 1, 1}, too_long); }),
             Catch::Contains("shorter than one horizon"));
  ManoeuvreOptions bad_opt;
  bad_opt.duration_s = -1;
  CHECK_THAT(error_of([&] { roll_out_manoeuvres(plant_step(spec), wheels_rolling(SingleTrackParams{}, 5.0), bad_opt); }),
             Catch::Contains("duration_s"));
}
