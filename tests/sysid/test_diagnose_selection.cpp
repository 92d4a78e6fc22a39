// mppi-fit diagnose: selection names the hidden effect (and only it), refuses to name one where
// none exists, and the corrected model cuts the held-out multi-step error. Oracle: the truth
// the synthetic recordings were generated with. A small seed x effect sweep (the full one is
// `mppi-fit diagnose sweep`, closed loop with MPPI).
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "dynamics/corrected_model.hpp"
#include "dynamics/with_effects.hpp"
#include "sysid/diagnose/diagnose.hpp"
#include "sysid/diagnose/synth.hpp"

using namespace mppi;
using namespace mppi::diagnose;

namespace {

DiagnoseResult diagnose_synthetic(const std::string& truth_text, std::uint64_t seed, std::vector<std::string>* ids,
                                  const std::string& out_dir = "") {
  EffectParams truth;
  *ids = parse_effect_assignments(truth_text, &truth);
  const DiagData d = prepare(synthesize_open_loop(truth, seed, 40.0), "synthetic " + truth_text);
  DiagnoseOptions o;
  o.out_dir = out_dir;
  o.plots = !out_dir.empty();
  return run_diagnosis(d, *make_model_family("single-track"), o);
}

}  // namespace

TEST_CASE("nothing is named on recordings without a hidden effect", "[diagnose]") {
  for (std::uint64_t seed : {3u, 4u, 5u}) {
    std::vector<std::string> ids;
    const DiagnoseResult r = diagnose_synthetic("", seed, &ids);
    INFO("seed " << seed << ": named " << (r.selection.selected.empty() ? "-" : r.selection.selected[0]));
    CHECK(r.selection.selected.empty());
    CHECK(r.headline_after == Approx(r.headline_before));
  }
}

TEST_CASE("seed x effect sweep: the hidden effect is named, nothing else, and held-out error halves", "[diagnose]") {
  const char* truths[] = {"steer_delay_s=0.08", "aero_drag_kgpm=0.4", "grip_change_time_s=12,grip_scale=0.6",
                          "throttle_lag_s=0.25", "steer_offset=0.08"};
  for (const char* truth : truths)
    for (std::uint64_t seed : {21u, 22u}) {
      std::vector<std::string> ids;
      const DiagnoseResult r = diagnose_synthetic(truth, seed, &ids);
      std::string named;
      for (const auto& s : r.selection.selected) named += s + " ";
      INFO(truth << " seed " << seed << ": named " << named << ", held-out reduction " << r.heldout_rmse_reduction);
      REQUIRE(!r.selection.selected.empty());
      CHECK(r.selection.selected[0] == ids[0]);
      for (const auto& s : r.selection.selected) CHECK(std::find(ids.begin(), ids.end(), s) != ids.end());
      CHECK(r.heldout_rmse_reduction >= 0.5);
    }
}

TEST_CASE("two hidden effects at once are both named; report and model file agree", "[diagnose]") {
  const auto dir = std::filesystem::temp_directory_path() / "mppi_test_diagnose_two";
  std::filesystem::remove_all(dir);
  std::vector<std::string> ids;
  const DiagnoseResult r = diagnose_synthetic("steer_delay_s=0.08,throttle_lag_s=0.25", 31, &ids, dir.string());
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
  CHECK(j["effects"].size() == effect_library().size());
  CHECK(!j["mismatch"].empty());
  const CorrectedModelFile f = load_corrected_model(j["model_file"].get<std::string>());
  CHECK(f.effects.steer_delay_s == Approx(0.08).margin(0.01));
  CHECK(f.effects.throttle_lag_s == Approx(0.25).margin(0.04));
  CHECK(std::filesystem::file_size(dir / "overlay.png") > 1000);
  CHECK(std::filesystem::file_size(dir / "residual_vs_regime.png") > 1000);
  std::filesystem::remove_all(dir);
}
