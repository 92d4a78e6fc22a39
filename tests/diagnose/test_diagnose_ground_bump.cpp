// The diagnosis names a hill at a place (ground_bump) on a recording of the independent evidence
// generator, whose hill is an elevation disc of the simulator's surface map (other code: slope by
// central differences, gravity as g sin(theta)), and finds its place, radius and height.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "diagnose/diagnose.hpp"
#include "diagnose/model_family.hpp"
#include "sysid/prepared_recording.hpp"
#include "evidence/generator.hpp"
#include "evidence/truth_effects.hpp"
#include "diagnose_fixtures.hpp"

using namespace mppi;
using namespace mppi::diagnose;

TEST_CASE("a raised-cosine hill on the track is named as a ground bump at its place", "[diagnose][slow]") {
  const mppi::test::ScratchDir dir("mppi_ground_bump_test");
  const evidence::EvidenceResult rec =
      mppi::test::independent_recording(dir / "bump.csv", "bump_height_m=0.6,bump_radius_m=12", 1, "gazebo", "ccw", "pursuit");

  // The hill's centre from the truth file: effects[0].sizes.centre_m = [x, y].
  std::ifstream truth_file(rec.truth_json);
  const nlohmann::json truth = nlohmann::json::parse(truth_file);
  const auto& centre = truth.at("effects").at(0).at("sizes").at("centre_m");
  const double cx = centre.at(0).get<double>(), cy = centre.at(1).get<double>();

  const DiagnoseResult r = mppi::test::diagnose_independent(rec);
  const std::string named = mppi::test::joined(r.selection.selected);
  const EffectParams& e = r.selection.final_effects;
  INFO("named: " << named << "; truth centre (" << cx << ", " << cy << "); fitted (" << e.bump_x_m << ", "
                 << e.bump_y_m << "), radius " << e.bump_radius_m << ", height " << e.bump_height_m
                 << "; held-out reduction " << r.heldout_rmse_reduction);
  REQUIRE(r.selection.selected.size() == 1);
  CHECK(r.selection.selected[0] == "ground_bump");
  CHECK(std::hypot(e.bump_x_m - cx, e.bump_y_m - cy) < 1.5);
  CHECK(e.bump_radius_m == Approx(12.0).margin(1.5));
  CHECK(e.bump_height_m == Approx(0.6).margin(0.1));
  CHECK(r.heldout_rmse_reduction > 0.3);
}

// The fast case of the one above: 30 s on the oval (two passes over the hill, one in the later
// validation block, one ending in the held-out part); the candidates: the hill, the tilted plane
// (the cruder account of the same physics), the longitudinal terms and the grip terms; no resamples.
TEST_CASE("a raised-cosine hill on a short recording is named as a ground bump at its place", "[diagnose]") {
  const mppi::test::ScratchDir dir("mppi_ground_bump_short_test");
  const evidence::EvidenceResult rec = mppi::test::independent_recording(
      dir / "bump.csv", "bump_height_m=0.6,bump_radius_m=12", 4, "gazebo", "ccw", "pursuit", 30.0);
  std::ifstream truth_file(rec.truth_json);
  const nlohmann::json truth = nlohmann::json::parse(truth_file);
  const auto& centre = truth.at("effects").at(0).at("sizes").at("centre_m");
  const double cx = centre.at(0).get<double>(), cy = centre.at(1).get<double>();

  DiagnoseOptions opt;
  opt.selection.candidates = {"ground_bump", "road_grade",      "aero_drag",       "rolling_resistance", "payload",
                              "grip_patch",  "friction_change", "tire_saturation", "throttle_gain",      "motor_speed"};
  opt.selection.stability_resamples = 0;
  const DiagnoseResult r = mppi::test::diagnose_independent(rec, opt);
  const std::string named = mppi::test::joined(r.selection.selected);
  const EffectParams& e = r.selection.final_effects;
  INFO("named: " << named << "; truth centre (" << cx << ", " << cy << "); fitted (" << e.bump_x_m << ", "
                 << e.bump_y_m << "), radius " << e.bump_radius_m << ", height " << e.bump_height_m
                 << "; held-out reduction " << r.heldout_rmse_reduction);
  REQUIRE(r.selection.selected.size() == 1);
  CHECK(r.selection.selected[0] == "ground_bump");
  CHECK(std::hypot(e.bump_x_m - cx, e.bump_y_m - cy) < 1.5);
  CHECK(e.bump_radius_m == Approx(12.0).margin(1.5));
  CHECK(e.bump_height_m == Approx(0.6).margin(0.1));
  CHECK(r.heldout_rmse_reduction > 0.3);
}

// A low hill (0.25 m over a 12-m radius) crossed a few times by the human driver on Marietta: on
// all the data the bump lowers the validation cost by about 10 %. Each stability resample holds
// only part of the passes over it; a search over places from scratch found the hill elsewhere in
// half of them, so it was left as "unstable". Refined from the place found on all the data, the
// resamples judge whether their data support the hill there.
TEST_CASE("a low hill found on all the data is stable across the resamples", "[diagnose][slow]") {
  const mppi::test::ScratchDir dir("mppi_ground_bump_stability_test");
  const DiagnoseResult r = mppi::test::diagnose_independent(
      mppi::test::independent_recording(dir / "bump.csv", "bump_height_m=0.25,bump_radius_m=12", 4, "marietta", "cw", "human"));
  const std::string named = mppi::test::joined(r.selection.selected);
  double inclusion = 0;
  for (const auto& c : r.selection.candidates)
    if (c.id == "ground_bump") inclusion = c.inclusion_frequency;
  INFO("named: " << named << "; ground_bump chosen in " << inclusion << " of the resamples");
  CHECK(inclusion >= 0.8);
  REQUIRE(r.selection.selected.size() == 1);
  CHECK(r.selection.selected[0] == "ground_bump");
}

// Large grip patches (grip x 0.5) on Marietta, pursuit driver. Refined from the patches found on
// all the data, a resample can grow a third disc to the largest radius (a range end) on its fewer
// passes; where that fit was kept for its lower cost, the resample was left without the patch and
// chose the tyre, and the tyre was named in place of the patch. The search's identified fit is
// kept instead, so enough resamples keep the patch for it to be stable. (The tyre is still chosen
// beside it in as many resamples and named with it: a wrong extra that the evidence grid counts.)
TEST_CASE("a resample keeps an identified grip patch over a refit that ends at a range limit", "[diagnose][slow]") {
  const mppi::test::ScratchDir dir("mppi_grip_patch_stability_test");
  const DiagnoseResult r = mppi::test::diagnose_independent(
      mppi::test::independent_recording(dir / "patches.csv", "grip_patch_scale=0.5", 1, "marietta", "ccw", "pursuit"));
  std::string log;
  for (const auto& l : r.selection.log) log += l + "\n";
  INFO("verdict: " << r.selection.verdict << "\n" << log);
  const auto patch = std::find_if(r.selection.candidates.begin(), r.selection.candidates.end(),
                                  [](const CandidateReport& c) { return c.id == "grip_patch"; });
  REQUIRE(patch != r.selection.candidates.end());
  CHECK(patch->inclusion_frequency >= SelectionOptions{}.min_inclusion_frequency);
  // In the correction: named, or part of it where a resample took another ground effect in its place.
  const auto in = [](const std::vector<std::string>& ids, const char* id) {
    return std::find(ids.begin(), ids.end(), id) != ids.end();
  };
  CHECK((in(r.selection.selected, "grip_patch") || in(r.selection.partial, "grip_patch")));
}
