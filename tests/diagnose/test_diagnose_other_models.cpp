// "Nominal + effects" around the other models of the library (dynamics/with_effects.hpp) and a diagnosis
// that starts from them. Oracles: the base model itself (no effects = identical steps; a
// steering gain = the base driven with the scaled command), the closed-form deceleration of
// an added drag, per-lane stepping for a batch that straddles a grip change, and the hidden
// truth of synthetic recordings from each base with a hidden effect.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "base/error.hpp"
#include "diagnose/diagnose.hpp"
#include "diagnose/model_family.hpp"
#include "diagnose/synth.hpp"
#include "dynamics/with_effects.hpp"
#include "sim/data_dir.hpp"
#include "diagnose_fixtures.hpp"

using namespace mppi;
using namespace mppi::diagnose;

namespace {

template <class M>
void start(const M& m, float* x, float vx) {
  VehicleState s;
  s.vx_mps = vx;
  s.yaw_rate_radps = 0.2f;
  m.init_state(s, x);
}

}  // namespace

TEST_CASE("four-wheel models with no effects step exactly like the base", "[diagnose][other_models]") {
  const DoubleTrack base;
  const DoubleTrackWithEffects wrapped{DoubleTrack()};
  float xb[DoubleTrack::kNx], xw[DoubleTrackWithEffects::kNx];
  start(base, xb, 5.f);
  start(wrapped, xw, 5.f);
  for (int k = 0; k < 400; ++k) {
    const float u[2] = {0.4f * std::sin(0.02f * k), 0.5f};
    base.step<1>(Batch<DoubleTrack::kNx, 1>{xb}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
    wrapped.step<1>(Batch<DoubleTrackWithEffects::kNx, 1>{xw}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
  }
  for (int i = 0; i < DoubleTrack::kNx; ++i) CHECK(xw[i] == Approx(xb[i]).margin(1e-6));
  CHECK(xw[DoubleTrackWithEffects::kTime] == Approx(0.8).margin(1e-4));
}

TEST_CASE("a steering gain is the base driven with the scaled command", "[diagnose][other_models]") {
  EffectParams e;
  e.steer_gain = 0.7;
  e.steer_offset = 0.05;
  const FullVehicle base;
  const FullVehicleWithEffects wrapped(FullVehicle(), e);
  float xb[FullVehicle::kNx], xw[FullVehicleWithEffects::kNx];
  start(base, xb, 4.f);
  start(wrapped, xw, 4.f);
  for (int k = 0; k < 300; ++k) {
    const float s = 0.5f * std::sin(0.03f * k);
    const float u[2] = {s, 0.4f}, ub[2] = {0.7f * s + 0.05f, 0.4f};
    base.step<1>(Batch<FullVehicle::kNx, 1>{xb}, ConstBatch<2, 1>{ub}, 0.002f, nullptr);
    wrapped.step<1>(Batch<FullVehicleWithEffects::kNx, 1>{xw}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
  }
  for (int i = 0; i < FullVehicle::kNx; ++i) CHECK(xw[i] == Approx(xb[i]).margin(1e-5));
}

TEST_CASE("added aero drag decelerates by c v|v| / m", "[diagnose][other_models]") {
  EffectParams e;
  e.aero_drag_kgpm = 0.8;
  const DoubleTrack base;
  const DoubleTrackWithEffects wrapped(DoubleTrack(), e);
  float xb[DoubleTrack::kNx], xw[DoubleTrackWithEffects::kNx];
  start(base, xb, 8.f);
  start(wrapped, xw, 8.f);
  const float u[2] = {0.f, 0.f};
  base.step<1>(Batch<DoubleTrack::kNx, 1>{xb}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
  wrapped.step<1>(Batch<DoubleTrackWithEffects::kNx, 1>{xw}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
  const double expected_dv = 0.8 * 8.0 * 8.0 / DoubleTrackParams{}.base.mass_kg * 0.002;
  CHECK(xb[state::kVx] - xw[state::kVx] == Approx(expected_dv).epsilon(1e-3));
}

TEST_CASE("a batch straddling a grip change steps each lane with its own grip", "[diagnose][other_models]") {
  EffectParams e;
  e.grip_change_time_s = 1.0;
  e.grip_scale = 0.5;
  const DoubleTrackWithEffects m(DoubleTrack(), e);
  constexpr int W = 4;
  constexpr int N = DoubleTrackWithEffects::kNx;
  float batch[N * W], lanes[W][N];
  for (int j = 0; j < W; ++j) {
    start(m, lanes[j], 6.f);
    lanes[j][DoubleTrackWithEffects::kTime] = j % 2 ? 2.f : 0.f;  // lanes 1, 3 after the change
    for (int i = 0; i < N; ++i) batch[i * W + j] = lanes[j][i];
  }
  float ub[2 * W];
  for (int k = 0; k < 200; ++k) {
    for (int j = 0; j < W; ++j) {
      ub[j] = 0.6f;       // hard steering: the grip matters
      ub[W + j] = 0.5f;
      const float u1[2] = {0.6f, 0.5f};
      m.step<1>(Batch<N, 1>{lanes[j]}, ConstBatch<2, 1>{u1}, 0.002f, nullptr);
    }
    m.step<W>(Batch<N, W>{batch}, ConstBatch<2, W>{ub}, 0.002f, nullptr);
  }
  for (int j = 0; j < W; ++j)
    for (int i = 0; i < N; ++i) CHECK(batch[i * W + j] == Approx(lanes[j][i]).margin(1e-5));
  // And the grip did change something: lanes 0 and 1 differ.
  CHECK(std::abs(lanes[0][state::kYawRate] - lanes[1][state::kYawRate]) > 0.05);
}

TEST_CASE("corrected-model file with a double-track nominal: round trip and mismatched --model", "[diagnose][other_models]") {
  CorrectedModelFile f;
  f.nominal_model = "double-track";
  f.double_track.front_track_m = 0.41;
  f.double_track.base.mass_kg = 19.5;
  f.effects.steer_lag_s = 0.05;
  f.selected = {"steer_lag"};
  const std::string text = corrected_model_to_yaml(f, "test");
  const CorrectedModelFile g = corrected_model_from_yaml(text, "round trip");
  CHECK(g.nominal_model == "double-track");
  CHECK(g.double_track.front_track_m == Approx(0.41));
  CHECK(g.double_track.base.mass_kg == Approx(19.5));
  CHECK(g.nominal.mass_kg == Approx(19.5));
  CHECK(g.effects.steer_lag_s == Approx(0.05));
  CHECK_THROWS_AS(corrected_model_from_yaml("model: corrected\nnominal: diff-drive\n", "bad"), Error);
  // The kinematic and network nominals round-trip too; a misspelt network key names itself.
  CorrectedModelFile k;
  k.nominal_model = "kinematic";
  k.kinematic.wheelbase_m = 0.61;
  CHECK(corrected_model_from_yaml(corrected_model_to_yaml(k), "kinematic").kinematic.wheelbase_m == Approx(0.61));
  CorrectedModelFile n;
  n.nominal_model = "autorally-nn";
  n.network_npz = "weights/net.npz";
  CHECK(corrected_model_from_yaml(corrected_model_to_yaml(n), "network").network_npz == "weights/net.npz");
  CHECK_THROWS_WITH(corrected_model_from_yaml("model: corrected\nnominal: autorally-nn\nnominal_params: {network: x}\n", "bad"),
                    Catch::Contains("unknown key 'network'"));
  const std::string path = (std::filesystem::temp_directory_path() / "mppi_dt_corrected.yaml").string();
  std::ofstream(path) << text;
  CHECK(make_model_family("double-track", path)->name() == "double-track");
  CHECK_THROWS_AS(make_model_family("single-track", path), Error);  // the file is a double-track one
  CHECK_THROWS_AS(make_model_family("diff-drive"), Error);
  std::filesystem::remove(path);
}

TEST_CASE("a parameter file is read as the parameters of the nominal model named", "[diagnose][other_models]") {
  const std::string double_track = sim::data_file("config/autorally_double_track.yaml");
  CHECK(make_model_family("single-track", sim::data_file("config/autorally_single_track.yaml"))->name() ==
        "single-track");
  CHECK(make_model_family("double-track", double_track)->name() == "double-track");
  CHECK(make_model_family("full-vehicle", sim::data_file("config/autorally_full_vehicle.yaml"))->name() ==
        "full-vehicle");
  CHECK(make_model_family("autorally-nn", sim::data_file("autorally/models/autorally_nnet_09_12_2018.npz"))->name() ==
        "autorally-nn");
  const std::string kinematic = (std::filesystem::temp_directory_path() / "mppi_kinematic_params.yaml").string();
  std::ofstream(kinematic) << "wheelbase_m: 0.61\n";
  CHECK(make_model_family("kinematic", kinematic)->name() == "kinematic");
  // Another model's keys are unknown keys.
  CHECK_THROWS_AS(make_model_family("single-track", double_track), Error);
  CHECK_THROWS_AS(make_model_family("single-track", kinematic), Error);
  CHECK_THROWS_AS(make_model_family("kinematic", double_track), Error);
  std::filesystem::remove(kinematic);
}

// The hidden effect (if any) of a recording generated with `model` is named from that model's
// own nominal, alone, and the corrected model at least halves the held-out error. The fast cases
// run on a shorter recording, with fewer candidates (the hidden effect's rivals) or without the
// stability resamples; `candidates` empty = the whole library.
static void check_other_nominal(const char* model, const char* truth_text, double duration_s = 40.0,
                                const std::vector<std::string>& candidates = {},
                                int stability_resamples = SelectionOptions{}.stability_resamples) {
  EffectParams truth;
  const std::vector<std::string> ids = parse_effect_assignments(truth_text, &truth);
  const PreparedRecording d = prepare(synthesize_open_loop(truth, 41, duration_s, {}, model), std::string(model) + " " + truth_text);
  DiagnoseOptions o;
  o.plots = false;
  o.selection.candidates = candidates;
  o.selection.stability_resamples = stability_resamples;
  const auto family = make_model_family(model);
  const DiagnoseResult r = run_diagnosis(d, *family, o);
  const std::string named = mppi::test::joined(r.selection.selected);
  INFO(model << " truth '" << truth_text << "': named " << named << ", held-out reduction " << r.heldout_rmse_reduction);
  if (ids.empty()) {
    CHECK(r.selection.selected.empty());
    return;
  }
  REQUIRE(!r.selection.selected.empty());
  CHECK(r.selection.selected[0] == ids[0]);
  CHECK(r.selection.selected.size() == 1);
  if (std::string(model) == "kinematic") {
    // No lateral velocity in this model (v_y is sensor noise only, a floor in the normalised
    // RMSE): judge the yaw rate the steering gain acts on, at 1 s.
    const auto& before = r.before[3];
    const auto& after = r.after[3];
    REQUIRE(before.horizon_s == Approx(1.0));
    INFO("yaw-rate RMSE at 1 s " << before.rmse[2] << " -> " << after.rmse[2]);
    CHECK(after.rmse[2] < 0.5 * before.rmse[2]);
  } else {
    CHECK(r.heldout_rmse_reduction >= 0.5);
  }
}

// 20-s recordings: the delay among the forms of the steering's dynamics and the chassis terms a
// double-track car could be missing, without resamples; the clean recording against the whole
// library.
TEST_CASE("diagnosis from a double-track nominal names a steering delay, nothing on a clean recording",
          "[diagnose][other_models]") {
  check_other_nominal("double-track", "steer_delay_s=0.08", 20.0,
                      {"steer_delay", "steer_lag", "steer_rate_limit", "steer_backlash", "steer_gain", "payload",
                       "weight_distribution", "tire_saturation", "aero_drag", "throttle_lag"},
                      0);
  check_other_nominal("double-track", "", 20.0);
}

TEST_CASE("diagnosis from a full-vehicle nominal names aerodynamic drag", "[diagnose][other_models][slow]") {
  check_other_nominal("full-vehicle", "aero_drag_kgpm=0.5");
}

// The fast case of the one above: 20 s, the drag among the longitudinal terms and a few others.
TEST_CASE("diagnosis from a full-vehicle nominal names aerodynamic drag on a short recording", "[diagnose][other_models]") {
  check_other_nominal("full-vehicle", "aero_drag_kgpm=0.5", 20.0,
                      {"aero_drag", "rolling_resistance", "payload", "motor_speed", "throttle_gain", "throttle_lag",
                       "throttle_offset", "steer_delay", "tire_saturation", "road_grade"},
                      0);
}

TEST_CASE("diagnosis from a kinematic nominal names a steering gain", "[diagnose][other_models]") {
  check_other_nominal("kinematic", "steer_gain=0.75");
}

TEST_CASE("diagnosis from a network nominal names a throttle lag", "[diagnose][other_models][slow]") {
  check_other_nominal("autorally-nn", "throttle_lag_s=0.2");
}

// The fast case of the one above: 20 s, the lag among the other forms of the throttle's dynamics
// and what else passed on the whole library (no tyre terms: the network has no tyres).
TEST_CASE("diagnosis from a network nominal names a throttle lag on a short recording", "[diagnose][other_models]") {
  check_other_nominal("autorally-nn", "throttle_lag_s=0.2", 20.0,
                      {"throttle_lag", "throttle_delay", "throttle_rate_limit", "throttle_offset", "throttle_gain",
                       "motor_voltage_sag", "speed_sensor_scale", "time_offset", "aero_drag", "steer_delay"},
                      0);
}

TEST_CASE("models without tyres refuse tyre effects and leave them out of the candidates", "[diagnose][other_models]") {
  EffectParams tyre;
  tyre.tyre_peak_scale = 0.8;
  CHECK_THROWS_AS(KinematicWithEffects(KinematicBicycle(), tyre), Error);
  const auto kinematic = make_model_family("kinematic");
  CHECK_FALSE(kinematic->supports("tire_saturation"));
  CHECK_FALSE(kinematic->supports("friction_change"));
  CHECK(kinematic->supports("steer_delay"));
  CHECK(make_model_family("double-track")->supports("tire_saturation"));
  const PreparedRecording d = prepare(synthesize_open_loop({}, 42, 20.0, {}, "kinematic"), "kinematic clean");
  DiagnoseOptions o;
  o.plots = false;
  o.selection.candidates = {"tire_saturation"};
  CHECK_THROWS_WITH(run_diagnosis(d, *kinematic, o), Catch::Contains("needs a tyre model"));
}
