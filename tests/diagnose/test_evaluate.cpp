// mppi-fit evaluate (diagnose/evaluate.hpp): a written corrected model scored on a recording.
// Oracles: the truth a synthetic recording was made with (the true effect, written here as a
// corrected-model file, must cut the error; no effect must change nothing), and the recording's
// own metadata for the refusals.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sysid/prepared_recording.hpp"
#include "diagnose/diagnose.hpp"
#include "diagnose/model_family.hpp"
#include "diagnose/evaluate.hpp"
#include "diagnose/synth.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/effects.hpp"

using namespace mppi;
using namespace mppi::diagnose;

namespace {
sim::Recording steer_delayed_recording() {
  EffectParams truth;
  parse_effect_assignments("steer_delay_s=0.1", &truth);
  return synthesize_open_loop(truth, 7, 20.0);
}
}  // namespace

TEST_CASE("evaluate scores the true effect better than the nominal model and no effect the same", "[diagnose][evaluate]") {
  const PreparedRecording d = prepare(steer_delayed_recording(), "synthetic steer delay");
  CorrectedModelFile with_truth;
  parse_effect_assignments("steer_delay_s=0.1", &with_truth.effects);
  EvaluateOptions o;
  o.rows = "0.5";
  const EvaluateResult r = evaluate_corrected_model(with_truth, "truth.yaml", d, o);
  INFO("normalised RMSE at 1 s: nominal " << r.headline_nominal << ", with the true delay " << r.headline_corrected);
  CHECK(r.rows_scored > 0);
  CHECK(r.rows_scored < d.rows());
  CHECK(r.reduction > 0.3);
  REQUIRE(r.nominal.size() == 5);  // one step, then 0.2, 0.5, 1, 2 s
  CHECK(r.nominal[0].horizon_s == Approx(d.dt_s));
  const CorrectedModelFile nothing;
  const EvaluateResult same = evaluate_corrected_model(nothing, "nominal.yaml", d, o);
  for (std::size_t i = 0; i < same.nominal.size(); ++i)
    CHECK(same.corrected[i].normalized_rmse == same.nominal[i].normalized_rmse);
  CHECK(same.headline_nominal == Approx(r.headline_nominal));  // the same rows, the same nominal model
  o.rows = "all";
  CHECK(evaluate_corrected_model(nothing, "nominal.yaml", d, o).rows_scored == d.rows());
}

TEST_CASE("evaluate refuses a model and a recording of different cars, naming what differs", "[diagnose][evaluate]") {
  sim::Recording rec = steer_delayed_recording();
  rec.metadata["vehicle"] = "dart_jetracer";
  rec.metadata["mass_kg"] = "1.58";
  rec.metadata["wheelbase_m"] = "0.1735";
  const PreparedRecording small_car = prepare(rec, "dart.csv");
  const CorrectedModelFile autorally;  // the library's single-track car: 21.9 kg
  CHECK_THROWS_WITH(check_model_matches_recording(autorally, "m.yaml", small_car),
                    Catch::Contains("mass [kg]") && Catch::Contains("1.58") && Catch::Contains("dart.csv"));
  rec.metadata.erase("mass_kg");
  CHECK_THROWS_WITH(check_model_matches_recording(autorally, "m.yaml", prepare(rec, "dart.csv")),
                    Catch::Contains("wheelbase [m]") && Catch::Contains("0.1735"));
  // The vehicle the file was fitted on against the recording's.
  rec.metadata.erase("wheelbase_m");
  CorrectedModelFile fitted = autorally;
  fitted.fitted_on["vehicle"] = "eth_lasgroup_rccar";
  CHECK_THROWS_WITH(check_model_matches_recording(fitted, "m.yaml", prepare(rec, "dart.csv")),
                    Catch::Contains("'eth_lasgroup_rccar'") && Catch::Contains("'dart_jetracer'"));
  fitted.fitted_on["vehicle"] = "dart_jetracer";
  CHECK_NOTHROW(check_model_matches_recording(fitted, "m.yaml", prepare(rec, "dart.csv")));
  // A model fitted on speed commands against a recording of throttle commands.
  fitted.fitted_on["throttle_command"] = "speed";
  CHECK_THROWS_WITH(check_model_matches_recording(fitted, "m.yaml", prepare(rec, "dart.csv")),
                    Catch::Contains("speed commands") && Catch::Contains("throttle commands"));
  // The same car's metadata passes.
  sim::Recording own = steer_delayed_recording();
  own.metadata["mass_kg"] = std::to_string(autorally.nominal.mass_kg);
  CHECK_NOTHROW(check_model_matches_recording(autorally, "m.yaml", prepare(own, "own.csv")));
}

TEST_CASE("evaluate checks the mass and wheelbase each nominal model has", "[diagnose][evaluate]") {
  sim::Recording rec = steer_delayed_recording();
  rec.metadata["mass_kg"] = "1.58";
  const PreparedRecording light = prepare(rec, "light.csv");
  rec.metadata.erase("mass_kg");
  rec.metadata["wheelbase_m"] = "0.1735";
  const PreparedRecording short_car = prepare(rec, "short.csv");
  CorrectedModelFile m;
  for (const std::string four_wheel : {models::DoubleTrackModel::kName, models::FullVehicleModel::kName}) {
    m.nominal_model = four_wheel;  // mass and geometry in the single-track core
    CHECK_THROWS_WITH(check_model_matches_recording(m, "m.yaml", light), Catch::Contains("mass [kg]"));
    CHECK_THROWS_WITH(check_model_matches_recording(m, "m.yaml", short_car), Catch::Contains("wheelbase [m]"));
  }
  m.nominal_model = models::Kinematic::kName;  // a wheelbase, no mass
  CHECK_NOTHROW(check_model_matches_recording(m, "m.yaml", light));
  CHECK_THROWS_WITH(check_model_matches_recording(m, "m.yaml", short_car), Catch::Contains("wheelbase [m]"));
  m.kinematic.wheelbase_m = 0.1735;
  CHECK_NOTHROW(check_model_matches_recording(m, "m.yaml", short_car));
  m.nominal_model = models::AutoRallyNetworkModel::kName;  // neither
  CHECK_NOTHROW(check_model_matches_recording(m, "m.yaml", light));
  CHECK_NOTHROW(check_model_matches_recording(m, "m.yaml", short_car));
}

TEST_CASE("a corrected-model file keeps its fitted_on section", "[diagnose][evaluate]") {
  CorrectedModelFile f;
  f.fitted_on["source"] = "run: 3 # left";
  f.fitted_on["vehicle"] = "autorally";
  const CorrectedModelFile back = corrected_model_from_yaml(corrected_model_to_yaml(f), "written");
  CHECK(back.fitted_on == f.fitted_on);
  CHECK_THROWS_WITH(corrected_model_from_yaml("model: corrected\nfitted_on: [1, 2]\n", "bad.yaml"),
                    Catch::Contains("bad.yaml") && Catch::Contains("fitted_on"));
}

TEST_CASE("a part cut off a recording keeps its rows, times and flags", "[diagnose][evaluate]") {
  const PreparedRecording d = prepare(steer_delayed_recording(), "synthetic");
  const std::size_t cut = d.rows() * 7 / 10;
  const PreparedRecording tail = slice_rows(d, cut, d.rows());
  REQUIRE(tail.rows() == d.rows() - cut);
  CHECK(tail.t.front() == d.t[cut]);
  CHECK(tail.vx.back() == d.vx.back());
  CHECK(tail.steer_over(0) == d.steer_over(cut));
  CHECK(tail.metadata == d.metadata);
  CHECK_THROWS_WITH(slice_rows(d, 10, 10), Catch::Contains("synthetic"));
  CHECK_THROWS(slice_rows(d, 0, d.rows() + 1));
}

TEST_CASE("a diagnosis scores its correction on test data that neither its fit nor its validation saw",
          "[diagnose][evaluate]") {
  const PreparedRecording all = prepare(steer_delayed_recording(), "synthetic steer delay");
  const std::size_t cut = all.rows() * 7 / 10;
  const PreparedRecording fit = slice_rows(all, 0, cut), test = slice_rows(all, cut, all.rows());
  DiagnoseOptions o;
  o.plots = false;
  o.selection.candidates = {"steer_delay", "throttle_lag"};
  o.selection.stability_resamples = 2;
  o.test = &test;
  o.test_name = "the last 30 %";
  const DiagnoseResult r = run_diagnosis(fit, *make_model_family("single-track"), o);
  REQUIRE(r.selection.selected == std::vector<std::string>{"steer_delay"});
  INFO("test: " << r.test.headline_nominal << " -> " << r.test.headline_corrected);
  CHECK(r.test.headline_corrected < 0.7 * r.test.headline_nominal);
  // The same figures from the corrected model, scored by evaluate on the test part alone.
  CorrectedModelFile f = make_model_family("single-track")->file(r.selection.final_effects, r.selection.selected);
  EvaluateOptions eo;
  const EvaluateResult e = evaluate_corrected_model(f, "corrected", test, eo);
  CHECK(e.headline_nominal == Approx(r.test.headline_nominal).epsilon(1e-6));
  CHECK(e.headline_corrected == Approx(r.test.headline_corrected).epsilon(1e-6));
  const auto j = nlohmann::json::parse(r.json);
  CHECK(j.at("test").at("data") == "the last 30 %");
  CHECK(j.at("test").at("rows") == test.rows());
  // The headline is the test figure; the held-out one (the veto's) is kept beside it.
  CHECK(j.at("headline").at("data") == "test");
  CHECK(j.at("headline").at("normalized_rmse_after").get<double>() == Approx(r.test.headline_corrected));
  CHECK(j.at("validation_headline").at("data") == "held-out");
  CHECK(j.at("validation_headline").at("normalized_rmse_after").get<double>() == Approx(r.headline_after));
}
