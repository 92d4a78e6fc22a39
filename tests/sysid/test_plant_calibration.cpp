// Calibration by open-loop prediction error (sysid/plant_calibration.hpp) and the scripted
// manoeuvres (sysid/manoeuvre_rollout.hpp): the fit recovers known parameters from data made
// by the plant with those parameters, and the shipped calibrated plant predicts the AutoRally
// network better than the uncalibrated one.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <tuple>

#include <unistd.h>

#include <catch2/catch.hpp>

#include "dynamics/autorally_nn.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/with_effects.hpp"
#include "dynamics/vehicle_params.hpp"
#include "error_of.hpp"
#include "mppi/vehicle_state.hpp"
#include "sysid/manoeuvre_rollout.hpp"
#include "sysid/plant_calibration.hpp"
#include "sysid/vehicle_estimation.hpp"
#include "test_data.hpp"

namespace {

using namespace mppi;
using namespace mppi::sysid;
using mppi::test::error_of;

// A scripted recording prepared as calibration and diagnosis read it.
PreparedRecording prepared(const sim::Recording& rec) { return prepare(rec, "manoeuvres", 3); }

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

TEST_CASE("command dither is white noise of the asked size on top of the same drive", "[sysid][calibration]") {
  // A car that never changes state: the scripted commands then depend on time only, so the
  // dithered recording minus the plain one is the dither itself (where no limit clips it).
  const RolloutStep frozen = [](std::vector<double>&, const double*, double) {};
  ManoeuvreOptions plain;
  plain.duration_s = 200;
  plain.initial_speed_mps = 6.0;  // inside the driver's regime: no recovery
  ManoeuvreOptions dithered = plain;
  dithered.steer_dither_std = 0.15;
  dithered.throttle_dither_std = 0.05;
  const std::vector<double> x0(7, 0.0);
  const sim::Recording a = roll_out_manoeuvres(frozen, x0, plain);
  const sim::Recording b = roll_out_manoeuvres(frozen, x0, dithered);
  for (const auto& [column, expected_std, lo, hi] :
       {std::tuple{"steer", 0.15, -0.99, 0.99}, std::tuple{"throttle", 0.05, -0.99, 0.65}}) {
    const auto& ua = a.column(column);
    const auto& ub = b.column(column);
    std::vector<double> d;
    for (std::size_t i = 0; i < ua.size(); ++i)
      if (ua[i] > lo + 3 * expected_std && ua[i] < hi - 3 * expected_std && ub[i] > lo && ub[i] < hi)
        d.push_back(ub[i] - ua[i]);  // (3 std from the limits, so clipping does not bias the sample)
    REQUIRE(d.size() > ua.size() / 3);
    double mean = 0, var = 0, lag1 = 0;
    for (double v : d) mean += v / static_cast<double>(d.size());
    for (double v : d) var += (v - mean) * (v - mean) / static_cast<double>(d.size());
    for (std::size_t i = 1; i < d.size(); ++i) lag1 += (d[i] - mean) * (d[i - 1] - mean);
    lag1 /= var * static_cast<double>(d.size() - 1);
    INFO(column << ": mean " << mean << ", std " << std::sqrt(var) << ", lag-1 autocorrelation " << lag1);
    CHECK(std::abs(mean) < 0.01);
    CHECK(std::sqrt(var) == Approx(expected_std).epsilon(0.05));
    CHECK(std::abs(lag1) < 0.05);  // white: independent from one sample to the next
  }
  dithered.steer_dither_std = 1.5;
  CHECK_THROWS_WITH(roll_out_manoeuvres(frozen, x0, dithered), Catch::Contains("dither"));
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
  const PreparedRecording rec = prepared(roll_out_manoeuvres(plant_step(truth_spec), wheels_rolling(truth, 5.0), o));

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
  const PreparedRecording rec = prepared(roll_out_manoeuvres(network_step(net), std::vector<double>(7, 0.0), o));
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

  // The actuated plant (a corrected-model file: per-axle tyres, steering servo and map) is
  // better again: measured 0.216 against 0.305 on the held-out seed of the fit.
  const CorrectedModelFile actuated =
      load_corrected_model(test::data_path("config/autorally_single_track_actuated.yaml"));
  REQUIRE(actuated.nominal_model == "single-track");
  const std::vector<std::string> actuator_names = {"steer_lag_s", "steer_cubic", "steer_offset"};
  const VehicleModelSpec actuated_plant = single_track_spec(actuated.nominal, actuator_names);
  const std::vector<double> actuator_values = {actuated.effects.steer_lag_s, actuated.effects.steer_cubic,
                                               actuated.effects.steer_offset};
  CHECK(actuated.effects.steer_lag_s > 0.02);  // the servo is in the file
  const double actuated_1s = prediction_error(actuated_plant, actuator_values, rec, scales).mean_nrmse;
  INFO("1-s NRMSE actuated " << actuated_1s);
  CHECK(actuated_1s < 0.85 * new_1s);

  // The effective-inertia plant (no actuator state, a heavier yaw inertia): as good as the
  // actuated one (measured 0.215), and it answers a steering step at once at about the
  // network's rate, where the actuated plant starts several times slower.
  const CorrectedModelFile heavy = load_corrected_model(test::data_path("config/autorally_single_track_effective_inertia.yaml"));
  REQUIRE(heavy.nominal_model == "single-track");
  CHECK(heavy.nominal.yaw_inertia_kgm2 > 2.0);
  CHECK(heavy.effects.steer_lag_s == 0);
  const std::vector<std::string> map_names = {"steer_cubic", "steer_offset"};
  const VehicleModelSpec heavy_plant = single_track_spec(heavy.nominal, map_names);
  const std::vector<double> map_values = {heavy.effects.steer_cubic, heavy.effects.steer_offset};
  const double heavy_1s = prediction_error(heavy_plant, map_values, rec, scales).mean_nrmse;
  INFO("1-s NRMSE effective inertia " << heavy_1s);
  CHECK(heavy_1s < 0.85 * new_1s);

  std::vector<double> x(AutoRallyNetwork::kNx, 0.0);
  x[state::kVx] = 6.0;
  const double u[2] = {0.3, 0.3};
  network_step(net)(x, u, 0.02);
  const double net_first = x[state::kYawRate];
  const double heavy_first = steering_step_yaw_rate(heavy_plant, map_values, 6.0, 0.3, 0.3, {0.02})[0];
  const double lagged_first = steering_step_yaw_rate(actuated_plant, actuator_values, 6.0, 0.3, 0.3, {0.02})[0];
  const double default_first = steering_step_yaw_rate(new_plant, {}, 6.0, 0.3, 0.3, {0.02})[0];
  INFO("yaw rate 20 ms after a steering step: network " << net_first << ", effective inertia " << heavy_first
                                                        << ", actuated " << lagged_first << ", default " << default_first);
  CHECK(std::abs(heavy_first - net_first) < 0.35 * net_first);  // measured 0.075 against 0.059
  CHECK(lagged_first < 0.5 * net_first);                         // 0.019
  CHECK(default_first > 1.5 * net_first);                        // 0.111
}

TEST_CASE("the shipped calibrated double-track and full vehicle predict the AutoRally network better than "
          "the uncalibrated ones",
          "[sysid][calibration]") {
  const AutoRallyNetwork net = AutoRallyNetwork::load(test::data_path("autorally/models/autorally_nnet_09_12_2018.npz"));
  ManoeuvreOptions o;
  o.duration_s = 20;
  o.seed = 77;
  const PreparedRecording rec = prepared(roll_out_manoeuvres(network_step(net), std::vector<double>(7, 0.0), o));
  const std::vector<double> scales = channel_scales(rec, {"vx", "vy", "yaw_rate"});
  const std::vector<std::string> none;
  auto error = [&](const VehicleModelSpec& spec) { return prediction_error(spec, {}, rec, scales).mean_nrmse; };
  const double dt_old = error(double_track_spec(
      load_double_track_params(test::data_path("config/autorally_double_track_uncalibrated.yaml")), none));
  const double dt_new =
      error(double_track_spec(load_double_track_params(test::data_path("config/autorally_double_track.yaml")), none));
  const double fv_old = error(full_vehicle_spec(
      load_full_vehicle_params(test::data_path("config/autorally_full_vehicle_uncalibrated.yaml")), none));
  const double fv_new =
      error(full_vehicle_spec(load_full_vehicle_params(test::data_path("config/autorally_full_vehicle.yaml")), none));
  INFO("1-s NRMSE double-track " << dt_old << " -> " << dt_new << ", full vehicle " << fv_old << " -> " << fv_new);
  // Measured on the fit's held-out seed: 0.438 -> 0.314 and 0.438 -> 0.317 (-28 %).
  CHECK(dt_new < 0.85 * dt_old);
  CHECK(fv_new < 0.85 * fv_old);
}

TEST_CASE("prediction error and calibration reject bad input by name", "[sysid][calibration]") {
  const VehicleModelSpec spec = single_track_spec(SingleTrackParams{}, {"tyre.D"});
  ManoeuvreOptions o;
  o.duration_s = 5;
  const PreparedRecording rec = prepared(roll_out_manoeuvres(plant_step(spec), wheels_rolling(SingleTrackParams{}, 5.0), o));
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

TEST_CASE("the single-track spec's actuator lags: step response, priming from the command history, "
          "and the corrected plant's (WithEffects) steps",
          "[sysid][calibration]") {
  const std::vector<std::string> lags = {"steer_lag_s", "throttle_lag_s"};
  const VehicleModelSpec spec = single_track_spec(SingleTrackParams{}, lags);
  REQUIRE(spec.nx == 11);  // + applied steer, applied throttle
  const std::vector<double> tau = {0.1, 0.25};
  SECTION("first-order step response: u (1 - exp(-t / tau))") {
    std::vector<double> x = wheels_rolling(SingleTrackParams{}, 6.0);
    x.resize(11, 0.0);
    const double u[2] = {0.5, 0.3};
    for (int k = 1; k <= 40; ++k) {
      spec.step(tau, x.data(), u, 0.02);
      const double t = 0.02 * k;
      INFO("t = " << t);
      REQUIRE(x[9] == Approx(0.5 * (1 - std::exp(-t / 0.1))).epsilon(1e-12));
      REQUIRE(x[10] == Approx(0.3 * (1 - std::exp(-t / 0.25))).epsilon(1e-12));
    }
  }
  SECTION("a start primes the lags with the commands before it") {
    ManoeuvreOptions o;
    o.duration_s = 5;
    sim::Recording rec = roll_out_manoeuvres(plant_step(single_track_spec(SingleTrackParams{}, {})),
                                             wheels_rolling(SingleTrackParams{}, 5.0), o);
    auto column = [&rec](const char* name) -> std::vector<double>& {
      return rec.data[static_cast<std::size_t>(std::find(rec.columns.begin(), rec.columns.end(), name) -
                                               rec.columns.begin())];
    };
    std::vector<double>& steer = column("steer");
    std::vector<double>& throttle = column("throttle");
    for (std::size_t i = 0; i < rec.rows(); ++i) {
      steer[i] = i < 100 ? 0.0 : 0.8;  // a steering step at row 100 (t = 2 s)
      throttle[i] = 0.2;
    }
    std::vector<double> x(11);
    const PreparedRecording stepped = prepared(rec);
    spec.init_state(stepped, 110, x.data());
    REQUIRE(spec.prime);
    spec.prime(tau, stepped, 110, x.data());
    CHECK(x[9] == Approx(0.8 * (1 - std::exp(-0.2 / 0.1))).epsilon(1e-9));  // 10 samples after the step
    CHECK(x[10] == Approx(0.2).epsilon(1e-12));
  }
  SECTION("the same trajectory as the simulator's corrected plant with these effects") {
    const std::vector<std::string> names = {"steer_lag_s", "throttle_lag_s", "steer_cubic", "steer_offset"};
    const std::vector<double> values = {0.1, 0.25, 0.3, 0.02};
    const VehicleModelSpec with_map = single_track_spec(SingleTrackParams{}, names);
    EffectParams e;
    e.steer_lag_s = 0.1;
    e.throttle_lag_s = 0.25;
    e.steer_cubic = 0.3;
    e.steer_offset = 0.02;
    const CorrectedSingleTrack plant(SingleTrack{}, e);
    std::vector<float> xf(CorrectedSingleTrack::kNx, 0.f);
    plant.init_state(VehicleState{0, 0, 0, 6, 0, 0, 0}, xf.data());
    std::vector<double> xd = wheels_rolling(SingleTrackParams{}, 6.0);
    xd.resize(11, 0.0);
    const double dt = 0.002;
    for (int k = 0; k < 500; ++k) {  // 1 s of a 1 Hz steering sine and a throttle step
      const double ud[2] = {0.6 * std::sin(2 * M_PI * k * dt), k < 100 ? 0.2 : 0.5};
      const float uf[2] = {static_cast<float>(ud[0]), static_cast<float>(ud[1])};
      plant.step<1>(Batch<CorrectedSingleTrack::kNx, 1>{xf.data()}, ConstBatch<2, 1>{uf}, static_cast<float>(dt),
                    nullptr);
      with_map.step(values, xd.data(), ud, dt);
    }
    CHECK(std::abs(xd[4]) > 0.05);  // the car did turn
    for (int i : {state::kVx, state::kVy, state::kYawRate})
      CHECK(xf[static_cast<std::size_t>(i)] == Approx(xd[static_cast<std::size_t>(i)]).margin(2e-3));
  }
}

TEST_CASE("joined recordings: no rollout spans a seam or starts on one, so a plant predicts its own pieces exactly",
          "[sysid][calibration]") {
  // Two pieces of one plant (with a 0.1-s steering lag, whose state is rebuilt from the commands
  // before each start) driven from different speeds and seeds, joined with a gap.
  const VehicleModelSpec spec = single_track_spec(SingleTrackParams{}, {"steer_lag_s"});
  const std::vector<double> lag = {0.1};
  const RolloutStep lagged = [&](std::vector<double>& x, const double u[2], double dt) { spec.step(lag, x.data(), u, dt); };
  auto piece = [&](double vx, std::uint64_t seed) {
    ManoeuvreOptions o;
    o.duration_s = 6;
    o.seed = seed;
    o.initial_speed_mps = vx;
    o.ff_offset = 0.04;
    o.ff_per_mps = 0.05;
    o.extra_state_columns = {"omega_front", "omega_rear"};
    std::vector<double> x0 = wheels_rolling(SingleTrackParams{}, vx);
    x0.push_back(0.0);  // applied steering
    x0.push_back(0.0);  // applied throttle (the spec carries both actuator states)
    REQUIRE(x0.size() == spec.state_names.size());
    sim::Recording r = roll_out_manoeuvres(lagged, x0, o);
    for (auto& col : r.data) col.resize(250);  // the next piece's first row falls on a rollout start (every 25)
    return r;
  };
  const sim::Recording a = piece(5.0, 3), b = piece(8.0, 4);
  const sim::Recording joined = join_recordings({a, b}, 10.0);
  REQUIRE(joined.rows() == 500);
  REQUIRE(joined.columns == a.columns);
  const std::vector<double>& t = joined.column("t");
  CHECK(t[250] - t[249] == Approx(10.0));
  CHECK(t[251] - t[250] == Approx(t[1] - t[0]));
  CHECK(joined.column("vx")[250] == Approx(b.column("vx")[0]));

  const std::vector<double> scales = channel_scales(prepared(joined), {"vx", "vy", "yaw_rate"});
  const PredictionError e = prediction_error(spec, lag, prepared(joined), scales);
  // Starts every 0.5 s (25 rows) whose 1-s window (50 rows) stays in its piece, after the piece's
  // first row (whose previous command is not known): rows 25..175 in the first, 275..425 in the
  // second; none on the seam (row 250) or across it.
  CHECK(e.rollouts == 7 + 7);
  CHECK(e.mean_nrmse < 1e-3);

  // The same rows re-timed without the gap: the position jump at the seam still cuts the pieces.
  sim::Recording seamless = joined;
  std::vector<double>& ts = seamless.data[0];
  for (std::size_t i = 0; i < ts.size(); ++i) ts[i] = 0.02 * static_cast<double>(i);
  CHECK(prediction_error(spec, lag, prepared(seamless), scales).rollouts == 7 + 7);
  // With the second piece's path moved to go on from the first one's end as well, nothing marks
  // the seam: rollouts cross it and fail.
  for (const char* c : {"x", "y"}) {
    const auto col = static_cast<std::size_t>(std::find(seamless.columns.begin(), seamless.columns.end(), c) -
                                              seamless.columns.begin());
    std::vector<double>& v = seamless.data[col];
    const double shift = v[249] - v[250];
    for (std::size_t i = 250; i < v.size(); ++i) v[i] += shift;
  }
  CHECK(prediction_error(spec, lag, prepared(seamless), scales).mean_nrmse > 0.02);

  CHECK_THAT(error_of([] { join_recordings({}); }), Catch::Contains("no recordings"));
  CHECK_THAT(error_of([&] { join_recordings({a, b}, 0.5); }), Catch::Contains("gap"));
  // A piece sampled at another rate would make the plan's steps wrong: refused by name.
  sim::Recording slow = b;
  for (double& v : slow.data[0]) v *= 2;  // every 0.04 s
  CHECK_THAT(error_of([&] { join_recordings({a, slow}); }),
             Catch::Contains("recording 2") && Catch::Contains("sampled every"));
}

TEST_CASE("a learned model's log is read with the commands the car received, and refused where it has holes",
          "[sysid][calibration]") {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("mppi_calibration_log_" + std::to_string(::getpid()) + ".csv")).string();
  auto write = [&](int hole_at_row) {
    sim::RecordingWriter w(path, {"applied_steer", "applied_throttle"});
    for (int i = 0; i < 10; ++i) {
      const double steer = i == hole_at_row ? std::nan("") : 0.5;
      w.write_row(std::vector<double>{0.02 * i, 0, 0, 0, 5, 0, 0, steer, 0.3, 0.1 * i, 0.2});
    }
    w.close();
  };
  write(-1);
  const sim::Recording rec = read_learned_model_log(path);
  CHECK(rec.column("steer")[4] == Approx(0.4));  // applied_steer, not the commanded 0.5
  CHECK(rec.column("throttle")[4] == Approx(0.2));
  write(6);  // the commanded steer is missing in data row 7; the applied one is there
  CHECK(read_learned_model_log(path).column("steer")[6] == Approx(0.6));
  {
    sim::RecordingWriter w(path, {});
    for (int i = 0; i < 10; ++i) w.write_row(std::vector<double>{0.02 * i, 0, 0, 0, i == 3 ? std::nan("") : 5.0, 0, 0, 0.1, 0.3});
    w.close();
  }
  CHECK_THAT(error_of([&] { read_learned_model_log(path); }),
             Catch::Contains(path) && Catch::Contains("data row 4") && Catch::Contains("vx"));
  std::filesystem::remove(path);
}

TEST_CASE("steering step response: inertia scales the first answer, a servo lag delays it, neither the end",
          "[sysid][calibration]") {
  const std::vector<double> leads = {0.02, 1.0};
  const VehicleModelSpec plain = single_track_spec(SingleTrackParams{}, {"yaw_inertia_kgm2"});
  const std::vector<double> r = steering_step_yaw_rate(plain, plain.nominal, 6.0, 0.3, 0.3, leads);
  REQUIRE(r.size() == 2);
  CHECK(r[0] > 0.02);  // the car answers within one 20-ms step
  CHECK(r[1] > 5 * r[0]);

  // The same by hand: 1 s of straight driving cannot move a lag-free plant, so it starts on the step.
  std::vector<double> x = wheels_rolling(SingleTrackParams{}, 6.0);
  const double u[2] = {0.3, 0.3};
  for (int k = 0; k < 50; ++k) plain.step(plain.nominal, x.data(), u, 0.02);
  CHECK(r[1] == Approx(x[state::kYawRate]).epsilon(1e-12));

  // Twice the yaw inertia: half the yaw acceleration in the first step (to first order in it).
  const std::vector<double> heavy = steering_step_yaw_rate(plain, {2 * plain.nominal[0]}, 6.0, 0.3, 0.3, leads);
  CHECK(heavy[0] == Approx(0.5 * r[0]).epsilon(0.1));

  // A 0.1-s steering lag: the wheels have turned by 1 - exp(-0.2) ~ 18 % after 20 ms, so the
  // first answer is much smaller; after 1 s the same as without it.
  const VehicleModelSpec lagged = single_track_spec(SingleTrackParams{}, {"steer_lag_s"});
  const std::vector<double> rl = steering_step_yaw_rate(lagged, {0.1}, 6.0, 0.3, 0.3, leads);
  CHECK(rl[0] < 0.25 * r[0]);
  CHECK(rl[1] == Approx(r[1]).epsilon(0.1));
}
