// mppi-fit diagnose: selection names the hidden effect (and only it), refuses to name one where
// none exists, and the corrected model cuts the held-out multi-step error. Oracle: the truth
// the synthetic recordings were generated with. A small seed x effect sweep (the full one is
// `mppi-fit diagnose sweep`, closed loop with MPPI).
#include <catch2/catch.hpp>

#include <cmath>
#include <algorithm>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "dynamics/corrected_model.hpp"
#include "dynamics/with_effects.hpp"
#include "diagnose/diagnose.hpp"
#include "diagnose/evaluate.hpp"
#include "diagnose/identifiability.hpp"
#include "diagnose/joint_refit.hpp"
#include "diagnose/synth.hpp"
#include "dynamics/single_track.hpp"
#include "diagnose_fixtures.hpp"
#include <random>

#include <tbb/global_control.h>

using namespace mppi;
using namespace mppi::diagnose;

namespace {

// A diagnosis of an open-loop recording of `duration_s` with the hidden effects `truth_text`;
// `selection`: the selection's options (the fast cases' fewer candidates and resamples).
DiagnoseResult diagnose_synthetic(const std::string& truth_text, std::uint64_t seed, std::vector<std::string>* ids,
                                  const std::string& out_dir = "", std::vector<std::string>* progress = nullptr,
                                  double duration_s = 40.0, const SelectionOptions& selection = {}) {
  EffectParams truth;
  *ids = parse_effect_assignments(truth_text, &truth);
  const PreparedRecording d = prepare(synthesize_open_loop(truth, seed, duration_s), "synthetic " + truth_text);
  DiagnoseOptions o;
  o.selection = selection;
  o.out_dir = out_dir;
  o.plots = !out_dir.empty();
  if (progress) o.selection.progress = [progress](const std::string& line) { progress->push_back(line); };
  return run_diagnosis(d, *make_model_family("single-track"), o);
}

}  // namespace

// 12-s recordings, against the whole library: every default candidate of the library is one (and
// the three joint ones of partner terms), none is named.
TEST_CASE("nothing is named on recordings without a hidden effect", "[diagnose]") {
  for (std::uint64_t seed : {3u, 4u, 5u}) {
    std::vector<std::string> ids;
    const DiagnoseResult r = diagnose_synthetic("", seed, &ids, "", nullptr, 12.0);
    INFO("seed " << seed << ": named " << (r.selection.selected.empty() ? "-" : r.selection.selected[0]));
    CHECK(r.selection.selected.empty());
    CHECK(r.headline_after == Approx(r.headline_before));
    std::size_t library_rows = 0;
    for (const auto& c : r.selection.candidates) library_rows += c.joint_of.empty();
    std::size_t default_candidates = 0;
    for (const auto& e : effect_library()) default_candidates += e.default_candidate;
    CHECK(library_rows == default_candidates);
    CHECK(r.selection.candidates.size() == default_candidates + 3);
  }
}

// One hidden effect, two seeds: it is named first, nothing else is named, and the held-out error
// at least halves.
static void check_named_alone(const char* truth) {
  for (std::uint64_t seed : {21u, 22u}) {
    std::vector<std::string> ids;
    const DiagnoseResult r = diagnose_synthetic(truth, seed, &ids);
    const std::string named = mppi::test::joined(r.selection.selected);
    INFO(truth << " seed " << seed << ": named " << named << ", held-out reduction " << r.heldout_rmse_reduction);
    REQUIRE(!r.selection.selected.empty());
    CHECK(r.selection.selected[0] == ids[0]);
    for (const auto& s : r.selection.selected) CHECK(std::find(ids.begin(), ids.end(), s) != ids.end());
    CHECK(r.heldout_rmse_reduction >= 0.5);
  }
}

TEST_CASE("seed x effect sweep: a steering delay is named alone and held-out error halves", "[diagnose][slow]") {
  check_named_alone("steer_delay_s=0.08");
}

TEST_CASE("seed x effect sweep: aerodynamic drag is named alone and held-out error halves", "[diagnose][slow]") {
  check_named_alone("aero_drag_kgpm=0.4");
}

TEST_CASE("seed x effect sweep: a grip change is named alone and held-out error halves", "[diagnose][slow]") {
  check_named_alone("grip_change_time_s=12,grip_scale=0.6");
}

TEST_CASE("seed x effect sweep: a throttle lag is named alone and held-out error halves", "[diagnose][slow]") {
  check_named_alone("throttle_lag_s=0.25");
}

TEST_CASE("seed x effect sweep: a steering offset is named alone and held-out error halves", "[diagnose][slow]") {
  check_named_alone("steer_offset=0.08");
}

// The sweep's five effects on 20-s recordings, one seed each, against the effect's rivals (the
// other forms of the same physics: delay / lag, drag / rolling resistance / grade, a grip change
// / the tyre's saturation / a payload, offset / gain); no resamples. On 20 s the held-out
// error falls by 40-60 % (the 40-s cases above: by half or more).
TEST_CASE("seed x effect sweep on short recordings: each effect is named alone and held-out error falls",
          "[diagnose]") {
  SelectionOptions selection;
  selection.candidates = {"steer_delay",     "steer_lag",   "throttle_delay", "throttle_lag",
                          "aero_drag",       "rolling_resistance", "road_grade", "friction_change",
                          "tire_saturation", "payload",     "steer_offset",   "steer_gain"};
  selection.stability_resamples = 0;
  for (const char* truth : {"steer_delay_s=0.08", "aero_drag_kgpm=0.4", "grip_change_time_s=8,grip_scale=0.6",
                            "throttle_lag_s=0.25", "steer_offset=0.08"}) {
    std::vector<std::string> ids;
    const DiagnoseResult r = diagnose_synthetic(truth, 21, &ids, "", nullptr, 20.0, selection);
    const std::string named = mppi::test::joined(r.selection.selected);
    INFO(truth << ": named " << named << ", held-out reduction " << r.heldout_rmse_reduction);
    REQUIRE(!r.selection.selected.empty());
    CHECK(r.selection.selected[0] == ids[0]);
    for (const auto& id : r.selection.selected) CHECK(std::find(ids.begin(), ids.end(), id) != ids.end());
    CHECK(r.heldout_rmse_reduction >= 0.3);
  }
}

// A 20-s recording; the candidates: each actuator's forms of dynamics, the partner terms of the
// three joint candidates, and the drag; two stability resamples.
TEST_CASE("two hidden effects at once are both named, report and model file agree", "[diagnose]") {
  const auto dir = std::filesystem::temp_directory_path() / "mppi_test_diagnose_two";
  std::filesystem::remove_all(dir);
  std::vector<std::string> ids;
  std::vector<std::string> progress;
  SelectionOptions selection;
  selection.candidates = {"steer_delay",   "steer_lag",       "steer_rate_limit", "throttle_delay", "throttle_lag",
                          "throttle_rate_limit", "steer_gain", "steer_offset",   "throttle_gain",  "throttle_offset",
                          "motor_freewheel", "drag_brake",    "aero_drag"};
  selection.stability_resamples = 2;
  const DiagnoseResult r =
      diagnose_synthetic("steer_delay_s=0.08,throttle_lag_s=0.25", 31, &ids, dir.string(), &progress, 20.0, selection);
  // Progress: the selection log line by line as it is written, and each stability resample.
  std::vector<std::string> logged, resamples;
  for (const auto& line : progress) (line.rfind("stability: resample ", 0) == 0 ? resamples : logged).push_back(line);
  CHECK(logged == r.selection.log);
  CHECK(static_cast<int>(resamples.size()) == selection.stability_resamples);
  std::vector<std::string> named = r.selection.selected;
  std::sort(named.begin(), named.end());
  std::sort(ids.begin(), ids.end());
  CHECK(named == ids);
  CHECK(r.heldout_rmse_reduction >= 0.5);
  // The files: report.json with the schema's keys, a corrected model that loads with the fit.
  std::ifstream in(dir / "report.json");
  const auto j = nlohmann::json::parse(in);
  for (const char* key : {"selected", "effects", "mismatch", "fit_before", "fit_after", "heldout_rmse_before",
                          "heldout_rmse_after", "model_file"})
    CHECK(j.contains(key));
  // One row per candidate effect, and the joint candidates (partner terms fitted together) apart.
  std::size_t library_rows = 0, joint_rows = 0;
  for (const auto& e : j["effects"]) (e.contains("joint_of") ? joint_rows : library_rows)++;
  CHECK(library_rows == selection.candidates.size());
  CHECK(joint_rows == 3);  // steering gain+offset, throttle gain+offset, freewheel+drag brake
  CHECK(!j["mismatch"].empty());
  const CorrectedModelFile f = load_corrected_model(j["model_file"].get<std::string>());
  CHECK(f.effects.steer_delay_s == Approx(0.08).margin(0.01));
  CHECK(f.effects.throttle_lag_s == Approx(0.25).margin(0.04));
  // mppi-fit evaluate on the written file and the same recording's held-out rows gives the
  // diagnosis' held-out figures.
  {
    EffectParams truth;
    parse_effect_assignments("steer_delay_s=0.08,throttle_lag_s=0.25", &truth);
    const PreparedRecording d = prepare(synthesize_open_loop(truth, 31, 20.0), "synthetic");
    EvaluateOptions eo;
    eo.rows = f.fitted_on.at("heldout");
    const EvaluateResult e = evaluate_corrected_model(f, "corrected_model.yaml", d, eo);
    CHECK(e.headline_nominal == Approx(r.headline_before).epsilon(1e-6));
    CHECK(e.headline_corrected == Approx(r.headline_after).epsilon(1e-6));
    REQUIRE(e.corrected.size() == r.after.size());
    for (std::size_t i = 0; i < r.after.size(); ++i) CHECK(e.corrected[i].normalized_rmse == Approx(r.after[i].normalized_rmse).epsilon(1e-6));
    CHECK(f.fitted_on.at("throttle_command") == "throttle");
  }
  CHECK(std::filesystem::file_size(dir / "overlay.png") > 1000);
  CHECK(std::filesystem::file_size(dir / "residual_vs_regime.png") > 1000);
  // report.html: self-contained, its embedded figures are report.json's, in the report's order.
  std::ifstream html_in(dir / "report.html");
  const std::string html((std::istreambuf_iterator<char>(html_in)), std::istreambuf_iterator<char>());
  CHECK(html.rfind("<!DOCTYPE html>", 0) == 0);
  CHECK(html.find("http://") == std::string::npos);
  CHECK(html.find("https://") == std::string::npos);
  CHECK(html.find("<img") == std::string::npos);  // both images became interactive figures
  CHECK(html.find("<table>") != std::string::npos);  // the Markdown tables are rendered
  const std::string open_tag = "<script type=\"application/json\" id=\"mppi-figures\">";
  const std::size_t a = html.find(open_tag);
  REQUIRE(a != std::string::npos);
  const std::size_t b = html.find("</script>", a);
  REQUIRE(b != std::string::npos);
  const auto embedded = nlohmann::json::parse(html.substr(a + open_tag.size(), b - a - open_tag.size()));
  REQUIRE(j.contains("figures"));
  REQUIRE(embedded.size() == 2);
  CHECK(embedded[0] == j["figures"]["residual_vs_regime"]);
  CHECK(embedded[1] == j["figures"]["overlay"]);
  CHECK(html.find("data-figure=\"0\"") < html.find("data-figure=\"1\""));
  // The overlay's vx panel holds the measured series.
  const auto& vx_panel = j["figures"]["overlay"]["panels"][1];
  CHECK(vx_panel["y_label"] == "vx [m/s]");
  REQUIRE(!vx_panel["series"].empty());
  CHECK(vx_panel["series"][0]["label"] == "measured");
  CHECK(vx_panel["series"][0]["x"].size() > 100);
  std::filesystem::remove_all(dir);
}

namespace {

// A straight-line drive written here, independent of the library's generators: the single-track
// model with the steering held at zero and the throttle stepping between a few levels, logged
// at 50 Hz with a little sensor noise.
sim::Recording straight_line_drive(std::uint64_t seed, double duration_s) {
  const SingleTrack car;
  float x[SingleTrack::kNx];
  VehicleState s0;
  s0.vx_mps = 3.f;
  car.init_state(s0, x);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  const double levels[] = {0.2, 0.45, 0.1, 0.35};
  sim::Recording rec;
  rec.columns = {sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end()};
  rec.data.assign(rec.columns.size(), {});
  const int rows = static_cast<int>(duration_s / 0.02);
  for (int k = 0; k < rows; ++k) {
    const float throttle = static_cast<float>(levels[(k / 150) % 4]);
    const double row[] = {0.02 * k, x[state::kX], x[state::kY], x[state::kYaw], x[state::kVx] + noise(rng),
                          x[state::kVy] + noise(rng), x[state::kYawRate] + noise(rng), 0.0, throttle};
    for (std::size_t c = 0; c < rec.columns.size(); ++c) rec.data[c].push_back(row[c]);
    const float u[2] = {0.f, throttle};
    for (int j = 0; j < 10; ++j) car.step<1>(Batch<SingleTrack::kNx, 1>{x}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
  }
  return rec;
}

}  // namespace

// A car can miss several things at once; the selection goes on past three rounds while each
// effect passes the selection thresholds (a cap of three would leave one of these out).
TEST_CASE("four hidden effects at once are all named, in four selection rounds", "[diagnose][slow]") {
  std::vector<std::string> ids;
  const DiagnoseResult r =
      diagnose_synthetic("steer_delay_s=0.08,throttle_lag_s=0.25,steer_offset=0.08,tyre_peak_scale=0.7", 31, &ids);
  std::vector<std::string> named = r.selection.selected;
  std::sort(named.begin(), named.end());
  std::sort(ids.begin(), ids.end());
  std::string log;
  for (const auto& line : r.selection.log) log += line + "\n";
  INFO(log);
  CHECK(named == ids);
  CHECK(std::any_of(r.selection.log.begin(), r.selection.log.end(),
                    [](const std::string& line) { return line.rfind("round 4: selected", 0) == 0; }));
  CHECK(r.heldout_rmse_reduction >= 0.5);
}

// The fast case of the one above: a 30-s recording, the four effects among their rivals (the
// other forms of each actuator's dynamics, the steering gain, the payload), no resamples.
TEST_CASE("four hidden effects at once are named in four selection rounds on a short recording", "[diagnose]") {
  std::vector<std::string> ids;
  SelectionOptions selection;
  selection.candidates = {"steer_delay", "steer_lag", "throttle_delay", "throttle_lag", "steer_offset",
                          "steer_gain",  "tire_saturation", "payload", "aero_drag"};
  selection.stability_resamples = 0;
  const DiagnoseResult r = diagnose_synthetic("steer_delay_s=0.08,throttle_lag_s=0.25,steer_offset=0.08,tyre_peak_scale=0.7",
                                              31, &ids, "", nullptr, 30.0, selection);
  std::vector<std::string> named = r.selection.selected;
  std::sort(named.begin(), named.end());
  std::sort(ids.begin(), ids.end());
  std::string log;
  for (const auto& line : r.selection.log) log += line + "\n";
  INFO(log);
  CHECK(named == ids);
  CHECK(std::any_of(r.selection.log.begin(), r.selection.log.end(),
                    [](const std::string& line) { return line.rfind("round 4: selected", 0) == 0; }));
  CHECK(r.heldout_rmse_reduction >= 0.5);
}

TEST_CASE("a straight-line recording cannot name steering or grip effects", "[diagnose]") {
  const PreparedRecording d = prepare(straight_line_drive(5, 40.0), "straight line");
  DiagnoseOptions o;
  o.plots = false;
  const DiagnoseResult r = run_diagnosis(d, *make_model_family("single-track"), o);
  CHECK(r.selection.selected.empty());
  for (const auto& c : r.selection.candidates) {
    INFO(c.id);
    const Excitation needs = effect_spec(c.joint_of.empty() ? c.id : c.joint_of[0]).needs;
    if (needs == Excitation::kSteer || needs == Excitation::kCornering) CHECK_FALSE(c.not_testable.empty());
    if (needs == Excitation::kThrottle) CHECK(c.not_testable.empty());
  }
}

TEST_CASE("a parameter at the end of its search range is a bound, not an estimate", "[diagnose]") {
  const EffectSpec& tyres = effect_spec("tire_saturation");
  EffectParams e;
  e.tyre_stiffness_scale = 5.0;  // the upper end of its search range [0.2, 5]
  CHECK_THAT(range_limit_shortfall(tyres, e), Catch::Contains("tyre_stiffness_scale") && Catch::Contains("upper"));
  e.tyre_stiffness_scale = 3.0;
  CHECK(range_limit_shortfall(tyres, e).empty());
  // A rate limit's lower end is its default (no limit): not a bound of an estimate.
  CHECK(range_limit_shortfall(effect_spec("steer_rate_limit"), EffectParams{}).empty());
  e = {};
  e.steer_slew_s = 3.0;
  CHECK_FALSE(range_limit_shortfall(effect_spec("steer_rate_limit"), e).empty());
  // A share's search range ends where its physical range does (closed [0, 1]): a whole
  // freewheeling motor is an estimate, not a bound.
  e = {};
  e.motor_freewheel_share = 1.0;
  CHECK(range_limit_shortfall(effect_spec("motor_freewheel"), e).empty());
  // A steering trim and a gyro bias need steering that varies, like the steering gain.
  CHECK(effect_spec("steer_offset").needs == Excitation::kSteer);
  CHECK(effect_spec("gyro_bias").needs == Excitation::kSteer);
}

TEST_CASE("an effect that the held-out part contradicts is not named and no model is written", "[diagnose]") {
  // A gyro bias in the first 70 % of a 20-s recording only: the training part shows it, the
  // held-out part (the last 30 %) does not.
  PreparedRecording d = prepare(synthesize_open_loop({}, 8, 20.0), "bias that goes away");
  const double t_end = d.t.back();
  for (std::size_t k = 0; k < d.rows(); ++k)
    if (d.t[k] < 0.7 * t_end) d.r[k] += 0.08;
  const auto out = std::filesystem::temp_directory_path() / "mppi_diag_unreliable";
  std::filesystem::remove_all(out);
  std::filesystem::create_directories(out);
  std::ofstream(out / "corrected_model.yaml") << "stale\n";
  DiagnoseOptions o;
  o.out_dir = out.string();
  o.plots = false;
  // The candidates: the bias and the terms that also move the yaw rate.
  o.selection.candidates = {"gyro_bias", "steer_offset",       "steer_asymmetry", "steer_gain",      "steer_delay",
                            "time_offset", "speed_sensor_scale", "payload",         "tire_saturation", "aero_drag"};
  const DiagnoseResult r = run_diagnosis(d, *make_model_family("single-track"), o);
  CHECK_FALSE(r.selection.reliable);
  CHECK(r.selection.selected.empty());
  CHECK_THAT(r.selection.verdict, Catch::Contains("no reliable correction"));
  CHECK_FALSE(std::filesystem::exists(out / "corrected_model.yaml"));
  bool bias_suspected = false;
  for (const auto& s : r.selection.suspected) bias_suspected |= s.id == "gyro_bias";
  CHECK(bias_suspected);
}

namespace {

// Circles of radius 8 m around the origin, written here independently of the library's effects:
// two single-track cars, the nominal one and one whose friction curve is halved, and the plant
// steps the slippery one while the car is on a disc of radius 3 m centred at one of
// `patch_centres_m` (a hard edge, where the library's patch has a smooth one). Steering follows
// the circle with a dither, the speed steps between 4 and 6 m/s; 50 Hz, a little sensor noise.
sim::Recording circles_over_patches(std::uint64_t seed, double duration_s,
                                    const std::vector<std::pair<double, double>>& patch_centres_m) {
  SingleTrackParams slippery_params;
  slippery_params.tyre.D *= 0.5;
  slippery_params.tyre.Sv *= 0.5;
  const SingleTrack nominal, slippery(slippery_params);
  float x[SingleTrack::kNx];
  VehicleState s0;
  s0.y_m = -8.f;
  s0.vx_mps = 4.f;
  nominal.init_state(s0, x);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01), dither(0.0, 0.08);
  sim::Recording rec;
  rec.columns = {sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end()};
  rec.data.assign(rec.columns.size(), {});
  const int rows = static_cast<int>(duration_s / 0.02);
  double steer_dither = 0;
  for (int k = 0; k < rows; ++k) {
    const double px = x[state::kX], py = x[state::kY];
    const double radius = std::hypot(px, py);
    const double tangent = std::atan2(py, px) + M_PI / 2 + 0.6 * (radius - 8.0) / 8.0;
    const double heading_error = std::remainder(tangent - x[state::kYaw], 2 * M_PI);
    if (k % 10 == 0) steer_dither = dither(rng);
    const float steer = static_cast<float>(std::clamp(1.5 * heading_error + 0.45 + steer_dither, -1.0, 1.0));
    const double target_mps = (k / 250) % 2 == 0 ? 4.0 : 6.0;
    const float throttle = static_cast<float>(std::clamp(0.3 + 0.5 * (target_mps - x[state::kVx]), -0.5, 0.9));
    const double row[] = {0.02 * k, px, py, x[state::kYaw], x[state::kVx] + noise(rng),
                          x[state::kVy] + noise(rng), x[state::kYawRate] + noise(rng), steer, throttle};
    for (std::size_t c = 0; c < rec.columns.size(); ++c) rec.data[c].push_back(row[c]);
    const float u[2] = {steer, throttle};
    for (int j = 0; j < 10; ++j) {
      const bool on_patch = std::any_of(patch_centres_m.begin(), patch_centres_m.end(), [&](const auto& c) {
        return std::hypot(x[state::kX] - c.first, x[state::kY] - c.second) < 3.0;
      });
      (on_patch ? slippery : nominal).step<1>(Batch<SingleTrack::kNx, 1>{x}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
    }
  }
  return rec;
}

}  // namespace

TEST_CASE("a patch of low grip is named as a place, not as a change in time", "[diagnose][slow]") {
  const PreparedRecording d = prepare(circles_over_patches(11, 60.0, {{8.0, 0.0}}), "circles over a patch");
  DiagnoseOptions o;
  o.plots = false;
  const DiagnoseResult r = run_diagnosis(d, *make_model_family("single-track"), o);
  const std::string named = mppi::test::joined(r.selection.selected);
  INFO("named: " << named << "; held-out reduction " << r.heldout_rmse_reduction);
  REQUIRE_FALSE(r.selection.selected.empty());
  CHECK(r.selection.selected[0] == "grip_patch");
  CHECK(std::find(r.selection.selected.begin(), r.selection.selected.end(), "friction_change") ==
        r.selection.selected.end());
  const EffectParams& e = r.selection.final_effects;
  CHECK(std::hypot(e.patch_x_m - 8.0, e.patch_y_m) < 1.5);
  CHECK(e.patch_radius_m == Approx(3.0).margin(1.0));
  CHECK(e.patch_grip_scale == Approx(0.5).margin(0.15));
  CHECK(e.patch2_radius_m == 0.0);  // one patch: no further disc
  CHECK(r.heldout_rmse_reduction > 0.3);
  // Located as a place before the correction; after it, no place stands out on the held-out part.
  auto at_a_place = [](const std::vector<Mismatch>& ms) {
    return std::any_of(ms.begin(), ms.end(), [](const Mismatch& m) { return m.where.rfind("place", 0) == 0; });
  };
  CHECK(at_a_place(r.mismatch));
  CHECK_FALSE(at_a_place(r.remaining));
  CHECK(r.explained_share[2] > 0.3);  // yaw rate: the grip shows in the turns
}

// The fast case of the one above: 30 s; the candidates: the patch, the change in time, the
// tyre and a few other terms the turns show; the default stability selection (six resamples).
TEST_CASE("a patch of low grip on a short recording is named as a place, not as a change in time", "[diagnose]") {
  const PreparedRecording d = prepare(circles_over_patches(11, 30.0, {{8.0, 0.0}}), "circles over a patch");
  DiagnoseOptions o;
  o.plots = false;
  o.selection.candidates = {"grip_patch", "friction_change", "tire_saturation", "payload", "steer_gain", "steer_delay",
                            "load_transfer"};
  const DiagnoseResult r = run_diagnosis(d, *make_model_family("single-track"), o);
  const std::string named = mppi::test::joined(r.selection.selected);
  std::string log;
  for (const auto& line : r.selection.log) log += line + "\n";
  const EffectParams& e = r.selection.final_effects;
  INFO(log << "named: " << named << "; disc (" << e.patch_x_m << ", " << e.patch_y_m << ", r " << e.patch_radius_m
           << ", grip " << e.patch_grip_scale << "); held-out reduction " << r.heldout_rmse_reduction);
  REQUIRE_FALSE(r.selection.selected.empty());
  CHECK(r.selection.selected[0] == "grip_patch");
  CHECK(std::find(r.selection.selected.begin(), r.selection.selected.end(), "friction_change") ==
        r.selection.selected.end());
  CHECK(std::hypot(e.patch_x_m - 8.0, e.patch_y_m) < 1.5);
  CHECK(e.patch_radius_m == Approx(3.0).margin(1.0));
  CHECK(e.patch_grip_scale == Approx(0.5).margin(0.15));
  CHECK(e.patch2_radius_m == 0.0);
  CHECK(r.heldout_rmse_reduction > 0.3);
  auto at_a_place = [](const std::vector<Mismatch>& ms) {
    return std::any_of(ms.begin(), ms.end(), [](const Mismatch& m) { return m.where.rfind("place", 0) == 0; });
  };
  CHECK(at_a_place(r.mismatch));
  CHECK_FALSE(at_a_place(r.remaining));
  CHECK(r.explained_share[2] > 0.3);
}

TEST_CASE("simplicity counts only the parameters a fit moved off their default", "[diagnose]") {
  using mppi::diagnose::FitResult;
  using mppi::diagnose::ParamEstimate;
  auto fit_of = [](std::vector<std::pair<double, double>> value_sd) {
    FitResult f;
    for (const auto& [v, sd] : value_sd) f.params.push_back(ParamEstimate{"p", "", v, sd});
    return f;
  };
  // rolling_resistance: F0 [N] and b [N s/m], both off at 0.
  const auto& rolling = mppi::effect_spec("rolling_resistance");
  REQUIRE(rolling.params.size() == 2);
  CHECK(mppi::diagnose::used_param_count(rolling, fit_of({{5.0, 1.0}, {0.1, 0.2}})) == 1);  // b within 2 sd of 0
  CHECK(mppi::diagnose::used_param_count(rolling, fit_of({{5.0, 1.0}, {3.0, 0.5}})) == 2);
  CHECK(mppi::diagnose::used_param_count(rolling, fit_of({{-2.5, 1.0}, {0.0, 0.0}})) == 2);  // no sd: counts
  CHECK(mppi::diagnose::used_param_count(rolling, fit_of({{0.1, 1.0}, {0.1, 1.0}})) == 1);  // at least one
  // grip_patch: its place (x, y) is searched over the data and always counts.
  const auto& patch = mppi::effect_spec("grip_patch");
  REQUIRE(patch.params.size() >= 3);
  std::vector<std::pair<double, double>> at_default;
  const mppi::EffectParams defaults;
  for (const auto& p : patch.params) at_default.emplace_back(defaults.*(p.member), 1.0);
  CHECK(mppi::diagnose::used_param_count(patch, fit_of(at_default)) == 2);
  // A second disc the fit added counts with its place and radius; a third it did not add, not at all.
  FitResult two_discs = fit_of(at_default);
  two_discs.effects.patch2_radius_m = 2.0;
  CHECK(mppi::diagnose::used_param_count(patch, two_discs) == 5);
}

TEST_CASE("two patches of one low-grip surface are named as one grip patch with two discs", "[diagnose][slow]") {
  // The same circles with slippery discs on opposite sides of the circle.
  const PreparedRecording d = prepare(circles_over_patches(12, 40.0, {{8.0, 0.0}, {-8.0, 0.0}}), "circles over two patches");
  DiagnoseOptions o;
  o.plots = false;
  const DiagnoseResult r = run_diagnosis(d, *make_model_family("single-track"), o);
  const std::string named = mppi::test::joined(r.selection.selected);
  const EffectParams& e = r.selection.final_effects;
  INFO("named: " << named << "; discs (" << e.patch_x_m << ", " << e.patch_y_m << ", r " << e.patch_radius_m
                 << "), (" << e.patch2_x_m << ", " << e.patch2_y_m << ", r " << e.patch2_radius_m << "), r3 "
                 << e.patch3_radius_m << "; held-out reduction " << r.heldout_rmse_reduction);
  REQUIRE(r.selection.selected.size() == 1);
  CHECK(r.selection.selected[0] == "grip_patch");
  REQUIRE(e.patch2_radius_m > 0.0);
  CHECK(e.patch3_radius_m == 0.0);
  // The two discs on the two patches, in either order.
  const double x_first = e.patch_x_m > 0 ? 8.0 : -8.0;
  CHECK(std::hypot(e.patch_x_m - x_first, e.patch_y_m) < 1.5);
  CHECK(std::hypot(e.patch2_x_m + x_first, e.patch2_y_m) < 1.5);
  CHECK(e.patch_radius_m == Approx(3.0).margin(1.0));
  CHECK(e.patch2_radius_m == Approx(3.0).margin(1.0));
  CHECK(e.patch_grip_scale == Approx(0.5).margin(0.15));
  CHECK(r.heldout_rmse_reduction > 0.3);
}

// The fast case of the one above: 20 s; the candidates of the one-patch fast case, no resamples.
TEST_CASE("two patches of one low-grip surface on a short recording are named as one grip patch with two discs",
          "[diagnose]") {
  const PreparedRecording d = prepare(circles_over_patches(12, 20.0, {{8.0, 0.0}, {-8.0, 0.0}}), "circles over two patches");
  DiagnoseOptions o;
  o.plots = false;
  o.selection.candidates = {"grip_patch", "friction_change", "tire_saturation", "payload", "steer_gain", "steer_delay",
                            "load_transfer"};
  o.selection.stability_resamples = 0;
  const DiagnoseResult r = run_diagnosis(d, *make_model_family("single-track"), o);
  const std::string named = mppi::test::joined(r.selection.selected);
  const EffectParams& e = r.selection.final_effects;
  std::string log;
  for (const auto& line : r.selection.log) log += line + "\n";
  INFO(log << "named: " << named << "; discs (" << e.patch_x_m << ", " << e.patch_y_m << ", r " << e.patch_radius_m
                 << "), (" << e.patch2_x_m << ", " << e.patch2_y_m << ", r " << e.patch2_radius_m << "), r3 "
                 << e.patch3_radius_m << "; held-out reduction " << r.heldout_rmse_reduction);
  REQUIRE(r.selection.selected.size() == 1);
  CHECK(r.selection.selected[0] == "grip_patch");
  REQUIRE(e.patch2_radius_m > 0.0);
  CHECK(e.patch3_radius_m == 0.0);
  const double x_first = e.patch_x_m > 0 ? 8.0 : -8.0;
  CHECK(std::hypot(e.patch_x_m - x_first, e.patch_y_m) < 1.5);
  CHECK(std::hypot(e.patch2_x_m + x_first, e.patch2_y_m) < 1.5);
  CHECK(e.patch_radius_m == Approx(3.0).margin(1.0));
  CHECK(e.patch2_radius_m == Approx(3.0).margin(1.0));
  CHECK(e.patch_grip_scale == Approx(0.5).margin(0.15));
  CHECK(r.heldout_rmse_reduction > 0.3);
}

TEST_CASE("the parallel selection gives the one-thread result", "[diagnose][slow]") {
  // Oracle: the same diagnosis with oneTBB held to one thread (candidates fitted one at a time).
  EffectParams truth;
  parse_effect_assignments("steer_delay_s=0.08", &truth);
  const PreparedRecording d = prepare(synthesize_open_loop(truth, 41, 20.0), "steering delay, 20 s");
  const auto family = make_model_family("single-track");
  const DiagnoseResult parallel = run_diagnosis(d, *family, DiagnoseOptions{});
  DiagnoseResult serial;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    serial = run_diagnosis(d, *family, DiagnoseOptions{});
  }
  CHECK(parallel.selection.log == serial.selection.log);
  CHECK(parallel.selection.selected == serial.selection.selected);
  REQUIRE(parallel.selection.final_params.size() == serial.selection.final_params.size());
  for (std::size_t i = 0; i < serial.selection.final_params.size(); ++i)
    CHECK(parallel.selection.final_params[i].value == serial.selection.final_params[i].value);
  CHECK(parallel.heldout_rmse_reduction == serial.heldout_rmse_reduction);
}

// The fast case of the one above: 10 s, the steering's forms of dynamics and a few others as
// candidates, two resamples (selected on in parallel too).
TEST_CASE("the parallel selection gives the one-thread result on a short recording", "[diagnose]") {
  EffectParams truth;
  parse_effect_assignments("steer_delay_s=0.08", &truth);
  const PreparedRecording d = prepare(synthesize_open_loop(truth, 41, 10.0), "steering delay, 10 s");
  const auto family = make_model_family("single-track");
  DiagnoseOptions o;
  o.selection.candidates = {"steer_delay", "steer_lag",  "steer_rate_limit", "steer_backlash",
                            "steer_gain",  "steer_offset", "throttle_lag",   "aero_drag"};
  o.selection.stability_resamples = 2;
  const DiagnoseResult parallel = run_diagnosis(d, *family, o);
  DiagnoseResult serial;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    serial = run_diagnosis(d, *family, o);
  }
  INFO("named: " << mppi::test::joined(parallel.selection.selected));
  CHECK(parallel.selection.selected == std::vector<std::string>{"steer_delay"});
  CHECK(parallel.selection.log == serial.selection.log);
  CHECK(parallel.selection.selected == serial.selection.selected);
  REQUIRE(parallel.selection.final_params.size() == serial.selection.final_params.size());
  for (std::size_t i = 0; i < serial.selection.final_params.size(); ++i)
    CHECK(parallel.selection.final_params[i].value == serial.selection.final_params[i].value);
  CHECK(parallel.heldout_rmse_reduction == serial.heldout_rmse_reduction);
}

TEST_CASE("the joint refit starts from the last selection round that holds named effects only",
          "[sysid][diagnose][selection]") {
  // A hand-built selection: round 1 took a steering delay, round 2 added a tyre saturation (not
  // named in the end), round 3 a steering trim; later rounds moved the delay.
  auto set = [](EffectParams e, const std::string& id, double v) {
    e.*(effect_spec(id).params[0].member) = v;
    return e;
  };
  auto get = [](const EffectParams& e, const std::string& id) { return e.*(effect_spec(id).params[0].member); };
  EffectParams r1 = set({}, "steer_delay", 0.08);
  EffectParams r2 = set(set(r1, "steer_delay", 0.15), "tire_saturation", 0.7);
  EffectParams r3 = set(set(set(r2, "steer_delay", 0.20), "tire_saturation", 0.6), "steer_offset", 0.05);
  const std::vector<SelectionRound> rounds = {{{"steer_delay"}, r1},
                                              {{"steer_delay", "tire_saturation"}, r2},
                                              {{"steer_delay", "tire_saturation", "steer_offset"}, r3}};
  const std::vector<std::string> final_chosen = rounds.back().chosen;
  const EffectParams fallback = set(set(set(set({}, "steer_delay", 0.3), "tire_saturation", 0.9), "steer_offset", 0.04),
                                    "throttle_delay", 0.11);

  SECTION("named: delay and trim -> round 1's delay, the trim and the rest from the fallback") {
    const EffectParams s = joint_refit_start(rounds, final_chosen, {"steer_delay", "steer_offset"}, fallback);
    CHECK(get(s, "steer_delay") == 0.08);
    CHECK(get(s, "steer_offset") == 0.04);
    CHECK(get(s, "tire_saturation") == 0.9);
    CHECK(get(s, "throttle_delay") == 0.11);
  }
  SECTION("named: delay and tyre -> round 2, the last round with nothing else") {
    const EffectParams s = joint_refit_start(rounds, final_chosen, {"tire_saturation", "steer_delay"}, fallback);
    CHECK(get(s, "steer_delay") == 0.15);
    CHECK(get(s, "tire_saturation") == 0.7);
    CHECK(get(s, "steer_offset") == 0.04);
  }
  SECTION("everything the selection kept is named -> the fallback (the final state)") {
    const EffectParams s =
        joint_refit_start(rounds, final_chosen, {"steer_offset", "steer_delay", "tire_saturation"}, fallback);
    for (const std::string id : {"steer_delay", "tire_saturation", "steer_offset", "throttle_delay"})
      CHECK(get(s, id) == get(fallback, id));
  }
  SECTION("no round holds named effects only -> the fallback") {
    const EffectParams s = joint_refit_start(rounds, final_chosen, {"steer_offset"}, fallback);
    CHECK(get(s, "steer_delay") == 0.3);
    CHECK(get(s, "steer_offset") == 0.04);
  }
}
