#include "diagnose/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "base/error.hpp"

namespace mppi::diagnose {
namespace {

// "Actuator dynamics" families: a pure delay, a first-order lag, a rate limit and a play of one
// actuator all hold back its response (EffectSpec::dynamics_of); at small sizes under sensor
// noise they are hard to tell apart. The sweep reports this looser count next to (never instead
// of) the strict one.
std::string actuator_family(const std::string& id) {
  for (const EffectSpec& e : effect_table())
    if (e.id == id && !e.dynamics_of.empty()) return e.dynamics_of + " actuator dynamics";
  return id;
}

double headline(const std::vector<HorizonMetrics>& ms, double horizon_s) {
  for (const auto& m : ms)
    if (std::abs(m.horizon_s - horizon_s) < 1e-9) return m.normalized_rmse;
  throw Error("sweep: no metrics at the headline horizon " + std::to_string(horizon_s) + " s");
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::string percent(int n, int of) {
  char b[48];
  std::snprintf(b, sizeof b, "%d/%d (%.0f %%)", n, of, of ? 100.0 * n / of : 0.0);
  return b;
}

}  // namespace

SweepRun run_sweep_case(const SynthOptions& so, const std::string& csv, const DiagnoseOptions& o,
                        const std::string& truth_label, const std::string& size) {
  if (!std::filesystem::exists(csv)) synthesize(so, csv);
  const PreparedRecording d = load_recording(csv);
  const PreparedRecording clean = load_recording(so.work_dir + "/run/log.csv");  // the noise-free states
  const auto family = make_model_family(so.nominal_model);
  const DiagnoseResult r = run_diagnosis(d, *family, o);

  SweepRun run;
  run.truth = truth_label;
  run.size = size;
  run.seed = static_cast<int>(so.seed);
  run.truth_ids = so.truth_ids;
  run.named = r.selection.selected;
  for (const auto& s : run.named) {
    const bool hit = std::find(run.truth_ids.begin(), run.truth_ids.end(), s) != run.truth_ids.end();
    (hit ? run.right : run.wrong) = true;
    bool family_hit = false;
    for (const auto& t : run.truth_ids) family_hit = family_hit || actuator_family(t) == actuator_family(s);
    (family_hit ? run.right_family : run.wrong_family) = true;
  }

  // Judge the correction on the held-out part, as run_diagnosis did, twice: against the
  // recording and against the noise-free states; and the hidden truth model the same ways.
  const Split split = make_split(d, o.holdout);
  std::vector<double> hs = {d.dt_s};
  hs.insert(hs.end(), o.horizons_s.begin(), o.horizons_s.end());
  const CorrectedModelFile truth_file = load_corrected_model(so.work_dir + "/truth_model.yaml");
  const auto nominal = family->make({});
  const auto corrected = family->make(r.selection.final_effects);
  const auto truth = model_family_of(truth_file)->make(truth_file.effects);
  run.before_h = horizon_metrics(*nominal, d, split.heldout, hs, 5, o.replay, &clean);
  run.after_h = horizon_metrics(*corrected, d, split.heldout, hs, 5, o.replay, &clean);
  run.truth_h = horizon_metrics(*truth, d, split.heldout, hs, 5, o.replay, &clean);
  const double h = o.headline_horizon_s;
  run.before = {r.headline_before, headline(run.before_h, h)};
  run.after = {r.headline_after, headline(run.after_h, h)};
  run.truth_model = {headline(horizon_metrics(*truth, d, split.heldout, hs, 5, o.replay), h),
                     headline(run.truth_h, h)};
  return run;
}

std::string sweep_run_json(const SweepRun& r) {
  using json = nlohmann::ordered_json;
  auto dump = [](const std::vector<HorizonMetrics>& ms) {
    json a = json::array();
    for (const auto& m : ms)
      a.push_back({{"horizon_s", m.horizon_s}, {"rmse", m.rmse}, {"normalized", m.normalized_rmse},
                   {"position_m", m.position_rmse_m}});
    return a;
  };
  auto scored = [](const ScoredRmse& s) { return json{{"measured", s.measured}, {"clean", s.clean}}; };
  json j;
  j["truth"] = r.truth;
  j["size"] = r.size;
  j["seed"] = r.seed;
  j["truth_ids"] = r.truth_ids;
  j["named"] = r.named;
  j["right"] = r.right;
  j["wrong"] = r.wrong;
  j["headline_before"] = scored(r.before);
  j["headline_after"] = scored(r.after);
  j["headline_truth_model"] = scored(r.truth_model);
  j["clean_before"] = dump(r.before_h);
  j["clean_after"] = dump(r.after_h);
  j["clean_truth_model"] = dump(r.truth_h);
  return j.dump();
}

std::string sweep_summary_markdown(const std::vector<SweepRun>& runs) {
  std::ostringstream md;
  md << "| truth | size | runs | right named | wrong named | median RMSE reduction (noise-free states) | "
        "median RMSE reduction (recording) | truth model's own (recording) |\n|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> keys;
  for (const auto& r : runs)
    if (std::find(keys.begin(), keys.end(), r.truth + "|" + r.size) == keys.end()) keys.push_back(r.truth + "|" + r.size);
  for (const auto& k : keys) {
    int n = 0, right = 0, wrong = 0;
    std::vector<double> red_clean, red_meas, red_truth;
    for (const auto& r : runs) {
      if (r.truth + "|" + r.size != k) continue;
      ++n;
      right += r.right;
      wrong += r.wrong;
      red_clean.push_back(r.reduction_clean());
      red_meas.push_back(r.reduction_measured());
      red_truth.push_back(r.before.measured > 0 ? 1 - r.truth_model.measured / r.before.measured : 0);
    }
    const auto bar = k.find('|');
    char line[320];
    std::snprintf(line, sizeof line, "| %s | %s | %d | %d | %d | %.1f %% | %.1f %% | %.1f %% |\n",
                  k.substr(0, bar).c_str(), k.substr(bar + 1).c_str(), n, right, wrong, 100 * median(red_clean),
                  100 * median(red_meas), 100 * median(red_truth));
    md << line;
  }
  int eff = 0, right = 0, wrong = 0, fam_right = 0, fam_wrong = 0, half_clean = 0, half_meas = 0, truth_half_meas = 0;
  int clean_runs = 0, clean_named = 0;
  std::vector<double> removed;
  for (const auto& r : runs) {
    if (r.truth == "none") {
      ++clean_runs;
      clean_named += !r.named.empty();
      continue;
    }
    ++eff;
    right += r.right;
    wrong += r.wrong;
    fam_right += r.right_family;
    fam_wrong += r.wrong_family;
    half_clean += r.reduction_clean() >= 0.5;
    half_meas += r.reduction_measured() >= 0.5;
    truth_half_meas += r.before.measured > 0 && r.truth_model.measured <= 0.5 * r.before.measured;
    removed.push_back(r.removable_removed());
  }
  md << "\nWith an effect (" << eff << " runs):\n"
     << "- right effect named: " << percent(right, eff) << "\n"
     << "- a wrong effect named: " << percent(wrong, eff) << "\n"
     << "- held-out 1-s RMSE reduced >= 50 %, scored against the noise-free states: " << percent(half_clean, eff) << "\n"
     << "- the same, scored against the recording (its sensor noise is a floor no model removes): "
     << percent(half_meas, eff) << "; the hidden truth model itself reaches it in " << percent(truth_half_meas, eff) << "\n";
  char b[160];
  std::snprintf(b, sizeof b, "- median share of the removable error removed (truth model = 100 %%): %.1f %%\n",
                100 * median(removed));
  md << b << "- counting a delay and a lag of one actuator as one effect: right " << percent(fam_right, eff)
     << ", wrong " << percent(fam_wrong, eff) << "\n\nNo effect: something named in " << clean_named << "/"
     << clean_runs << ".\n";
  return md.str();
}

}  // namespace mppi::diagnose
