#include "diagnose/evidence_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "base/error.hpp"
#include "evidence/truth_effects.hpp"

namespace mppi::diagnose {
namespace {

// 2-effect combinations: one actuator or sensor effect with one force or chassis effect.
const std::vector<std::pair<std::string, std::string>>& pair_list() {
  static const std::vector<std::pair<std::string, std::string>> p = {
      {"steer_delay", "aero_drag_vector"},   {"throttle_gain", "steer_gain_offset"},
      {"payload", "hill"},                   {"battery_sag", "steer_rate_limit"},
      {"gyro_bias", "steer_backlash"},       {"throttle_delay", "axle_rolling_resistance"},
      {"speed_sensor_scale", "steer_cubic"}, {"sensor_time_offset", "grip_patches"},
  };
  return p;
}

double headline(const std::vector<HorizonMetrics>& ms, double horizon_s) {
  for (const auto& m : ms)
    if (std::abs(m.horizon_s - horizon_s) < 1e-9) return m.normalized_rmse;
  throw Error("evidence sweep: no metrics at the headline horizon");
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string pct(int n, int of) {
  char b[48];
  // One decimal, so that a share just below a round figure is not shown as it (206/230: 89.6 %).
  std::snprintf(b, sizeof b, "%d/%d (%.1f %%)", n, of, of ? 100.0 * n / of : 0.0);
  return b;
}

std::string joined(const std::vector<std::string>& v, const char* sep = "+") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s.empty() ? "-" : s;
}

}  // namespace

std::string EvidenceCase::label() const {
  return (effects.empty() ? std::string("none") : joined(effects, "+")) + "_" + size + "_s" + std::to_string(seed);
}

EvidenceGrid reduced_evidence_grid() {
  EvidenceGrid g;
  g.seeds = 1;
  g.pairs = 3;
  g.clean = 4;
  return g;
}

std::vector<EvidenceCase> evidence_cases(const EvidenceGrid& g) {
  using evidence::truth_effect_catalogue;
  std::vector<EvidenceCase> single, pairs, clean;
  for (const auto& name : g.effects) evidence::truth_effect_info(name);  // throws for unknown names
  for (const auto& size : g.sizes)
    if (size != "small" && size != "large") throw Error("evidence sweep: sizes are small and large, not '" + size + "'");
  for (int s = 1; s <= g.seeds; ++s)
    for (const auto& size : g.sizes)
      for (const auto& info : truth_effect_catalogue()) {
        const bool asked = std::find(g.effects.begin(), g.effects.end(), info.name) != g.effects.end();
        if (g.effects.empty() ? !info.in_grid : !asked) continue;
        single.push_back({{info.name}, size, size == "small" ? info.small : info.large, s});
      }
  const int n_pairs = std::min<int>(g.pairs, static_cast<int>(pair_list().size()));
  for (int s = 1; s <= g.seeds; ++s)
    for (int i = 0; i < n_pairs; ++i) {
      const auto& [a, b] = pair_list()[static_cast<std::size_t>(i)];
      pairs.push_back({{a, b}, "pair", evidence::truth_effect_info(a).large + "," + evidence::truth_effect_info(b).large, s});
    }
  for (int s = 1; s <= g.clean; ++s) clean.push_back({{}, "clean", "", 100 + s});
  // Interleaved (seed-major): a sweep cut short still has every kind of case in it.
  std::vector<EvidenceCase> out;
  std::size_t i = 0, j = 0, k = 0;
  const std::size_t total = single.size() + pairs.size() + clean.size();
  const std::size_t every = std::max<std::size_t>(1, single.size() / std::max<std::size_t>(1, clean.size() + pairs.size()));
  while (out.size() < total) {
    for (std::size_t n = 0; n < every && i < single.size(); ++n) out.push_back(single[i++]);
    if (k < clean.size() && (k <= j || j >= pairs.size())) out.push_back(clean[k++]);
    else if (j < pairs.size()) out.push_back(pairs[j++]);
  }
  return out;
}

void score_evidence_run(const std::vector<evidence::PlacePasses>& place_passes, EvidenceRun* r) {
  EvidenceRun& run = *r;
  run.acceptable.clear();
  run.crossed_once.clear();
  run.wrong = false;
  bool all_out = true, all_named = true, all_named_strict = true, any_required = false;
  for (const auto& name : run.c.effects) {
    const auto& ids = evidence::truth_effect_info(name).table_ids;
    run.acceptable.insert(run.acceptable.end(), ids.begin(), ids.end());
    if (ids.empty()) continue;
    all_out = false;
    bool hit = false;
    for (const auto& id : ids) hit = hit || std::find(run.named.begin(), run.named.end(), id) != run.named.end();
    all_named_strict = all_named_strict && hit;
    const auto place = std::find_if(place_passes.begin(), place_passes.end(),
                                    [&](const evidence::PlacePasses& p) { return p.effect == name; });
    if (place != place_passes.end() && place->crossed_once()) {
      run.crossed_once.push_back(name);
      continue;
    }
    any_required = true;
    all_named = all_named && hit;
  }
  run.out_of_library = !run.c.effects.empty() && all_out;
  for (const auto& n : run.named)
    if (std::find(run.acceptable.begin(), run.acceptable.end(), n) == run.acceptable.end()) run.wrong = true;
  const bool nothing_required = run.c.effects.empty() || all_out;
  run.right_strict = nothing_required ? run.named.empty() : all_named_strict;
  run.right = nothing_required ? run.named.empty() : any_required ? all_named : !run.wrong;
}

EvidenceRun run_evidence_case(const EvidenceCase& c, const std::string& dir, double duration_s,
                              const DiagnoseOptions& o, const std::string& vehicle_yaml, double rate_hz) {
  EvidenceRun run;
  run.c = c;
  try {
    evidence::EvidenceOptions eo;
    eo.seed = static_cast<std::uint64_t>(c.seed);
    eo.duration_s = duration_s;
    eo.log_dt_s = evidence::log_interval_s(rate_hz);
    eo.vehicle_yaml = vehicle_yaml;
    eo.truth_names = evidence::set_truth_effects(c.assignments, &eo.truth);
    const std::string csv = dir + "/" + c.label() + ".csv";
    const evidence::EvidenceResult g = evidence::generate_evidence(eo, csv);
    run.track = g.track;
    run.direction = g.direction;
    run.driver = g.driver;
    run.crashes = g.crashes;

    const PreparedRecording d = load_recording(csv);
    const PreparedRecording clean = load_recording(g.clean_csv);
    // The nominal is the vehicle file the generator's car was built from: an effect-free
    // recording then has the nominal physics (computed by other code), as on a real car whose
    // parameter file is known.
    const auto family = make_model_family("single-track", g.vehicle_yaml);
    const DiagnoseResult r = run_diagnosis(d, *family, o);
    run.named = r.selection.selected;
    for (const auto& id : run.named) {
      double inclusion = -1;
      for (const auto& cand : r.selection.candidates)
        if (cand.id == id) inclusion = cand.inclusion_frequency;
      run.named_inclusion.push_back(inclusion);
    }
    for (const auto& s : r.selection.suspected) run.suspected.push_back(s.id);
    run.partial = r.selection.partial;
    run.ambiguous = r.selection.ambiguous;
    run.unexplained = static_cast<int>(r.unexplained.size());

    score_evidence_run(g.place_passes, &run);

    const Split split = make_split(d, o.holdout);
    std::vector<double> hs = {d.dt_s};
    hs.insert(hs.end(), o.horizons_s.begin(), o.horizons_s.end());
    const auto nominal = family->make({});
    const auto corrected = family->make(r.selection.final_effects);
    run.before_clean = headline(horizon_metrics(*nominal, d, split.heldout, hs, 5, o.replay, &clean), o.headline_horizon_s);
    run.after_clean = headline(horizon_metrics(*corrected, d, split.heldout, hs, 5, o.replay, &clean), o.headline_horizon_s);
  } catch (const std::exception& e) {
    run.error = e.what();
  }
  return run;
}

std::string evidence_run_json(const EvidenceRun& r) {
  nlohmann::ordered_json j;
  j["label"] = r.c.label();
  j["effects"] = r.c.effects;
  j["size"] = r.c.size;
  j["seed"] = r.c.seed;
  j["assignments"] = r.c.assignments;
  j["track"] = r.track;
  j["direction"] = r.direction;
  j["driver"] = r.driver;
  j["crashes"] = r.crashes;
  j["named"] = r.named;
  j["named_inclusion"] = r.named_inclusion;
  j["suspected"] = r.suspected;
  j["partial"] = r.partial;
  j["ambiguous"] = r.ambiguous;
  j["unexplained"] = r.unexplained;
  j["acceptable_ids"] = r.acceptable;
  j["out_of_library"] = r.out_of_library;
  j["crossed_once"] = r.crossed_once;
  j["right"] = r.right;
  j["right_strict"] = r.right_strict;
  j["wrong"] = r.wrong;
  j["heldout_1s_nrmse_clean_before"] = r.before_clean;
  j["heldout_1s_nrmse_clean_after"] = r.after_clean;
  j["reduction"] = r.reduction();
  j["corrected_worse"] = r.corrected_worse();
  if (!r.error.empty()) j["error"] = r.error;
  return j.dump();
}

std::vector<EvidenceRun> read_evidence_runs(const std::string& jsonl_path) {
  std::ifstream in(jsonl_path);
  if (!in) throw Error(jsonl_path + ": cannot open");
  std::vector<EvidenceRun> runs;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    try {
      const auto j = nlohmann::json::parse(line);
      EvidenceRun r;
      r.c.effects = j.at("effects").get<std::vector<std::string>>();
      r.c.size = j.at("size");
      r.c.seed = j.at("seed");
      r.c.assignments = j.at("assignments");
      r.track = j.at("track");
      r.direction = j.at("direction");
      r.driver = j.at("driver");
      r.crashes = j.at("crashes");
      r.named = j.at("named").get<std::vector<std::string>>();
      if (j.contains("named_inclusion")) r.named_inclusion = j.at("named_inclusion").get<std::vector<double>>();
      r.suspected = j.at("suspected").get<std::vector<std::string>>();
      if (j.contains("partial")) r.partial = j.at("partial").get<std::vector<std::string>>();
      if (j.contains("ambiguous")) r.ambiguous = j.at("ambiguous").get<std::string>();
      if (j.contains("unexplained")) r.unexplained = j.at("unexplained").get<int>();
      r.acceptable = j.at("acceptable_ids").get<std::vector<std::string>>();
      r.out_of_library = j.at("out_of_library");
      r.right = j.at("right");
      // runs.jsonl of an older sweep: no place effect excepted
      r.right_strict = j.contains("right_strict") ? j.at("right_strict").get<bool>() : r.right;
      if (j.contains("crossed_once")) r.crossed_once = j.at("crossed_once").get<std::vector<std::string>>();
      r.wrong = j.at("wrong");
      r.before_clean = j.at("heldout_1s_nrmse_clean_before");
      r.after_clean = j.at("heldout_1s_nrmse_clean_after");
      if (j.contains("error")) r.error = j.at("error");
      runs.push_back(r);
    } catch (const nlohmann::json::exception& e) {
      throw Error(jsonl_path + ":" + std::to_string(n) + ": " + e.what());
    }
  }
  return runs;
}

namespace {

struct Totals {
  int with_effect = 0, right = 0, right_strict = 0, crossed_once = 0, wrong = 0, worse = 0, clean_runs = 0,
      clean_named = 0, errors = 0;
  // Runs with an effect that report an unexplained mismatch / a partial correction / an ambiguous pair.
  int unexplained = 0, partial = 0, ambiguous = 0;
  std::vector<double> reductions;
};

Totals totals_of(const std::vector<EvidenceRun>& runs) {
  Totals t;
  for (const auto& r : runs) {
    if (!r.error.empty()) {
      ++t.errors;
      continue;
    }
    t.worse += r.corrected_worse();
    if (r.c.effects.empty()) {
      ++t.clean_runs;
      t.clean_named += !r.named.empty();
      continue;
    }
    ++t.with_effect;
    t.right += r.right;
    t.right_strict += r.right_strict;
    t.crossed_once += !r.crossed_once.empty();
    t.wrong += r.wrong;
    t.unexplained += r.unexplained > 0;
    t.partial += !r.partial.empty();
    t.ambiguous += !r.ambiguous.empty();
    if (!r.out_of_library) t.reductions.push_back(r.reduction());
  }
  return t;
}

}  // namespace

std::string evidence_summary_markdown(const std::vector<EvidenceRun>& runs) {
  std::ostringstream md;
  md << "| hidden effect(s) | size | runs | right named | wrong named | corrected worse | median 1-s RMSE "
        "reduction (noise-free) | named (per run) |\n|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> keys;
  auto key_of = [](const EvidenceRun& r) { return joined(r.c.effects) + "|" + r.c.size; };
  for (const auto& r : runs)
    if (std::find(keys.begin(), keys.end(), key_of(r)) == keys.end()) keys.push_back(key_of(r));
  for (const auto& k : keys) {
    int n = 0, right = 0, wrong = 0, worse = 0;
    std::vector<double> red;
    std::string named;
    for (const auto& r : runs) {
      if (key_of(r) != k) continue;
      if (!r.error.empty()) {
        named += (named.empty() ? "" : "; ") + std::string("error");
        continue;
      }
      ++n;
      right += r.right;
      wrong += r.wrong;
      worse += r.corrected_worse();
      red.push_back(r.reduction());
      std::string this_run = joined(r.named);
      if (!r.suspected.empty()) this_run += " (suspected " + joined(r.suspected) + ")";
      named += (named.empty() ? "" : "; ") + this_run;
    }
    const auto bar = k.find('|');
    char line[256];
    std::snprintf(line, sizeof line, "| %s | %s | %d | %d | %d | %d | %.1f %% | ", k.substr(0, bar).c_str(),
                  k.substr(bar + 1).c_str(), n, right, wrong, worse, 100 * median(red));
    md << line << named << " |\n";
  }
  const Totals t = totals_of(runs);
  char b[160];
  std::snprintf(b, sizeof b, "%.1f %%", 100 * median(t.reductions));
  md << "\n| measure | bar | measured |\n|---|---|---|\n"
     << "| right effect named (with an effect; out of library: nothing named; a place effect the car crossed "
        "once need not be named) | >= 90 % | " << pct(t.right, t.with_effect) << " |\n"
     << "| right effect named, place effects crossed once included (" << t.crossed_once << " run(s) with one) | - | "
     << pct(t.right_strict, t.with_effect) << " |\n"
     << "| a wrong effect named | <= 10 % | " << pct(t.wrong, t.with_effect) << " |\n"
     << "| something named on effect-free recordings | 0 | " << t.clean_named << "/" << t.clean_runs << " |\n"
     << "| corrected worse than nominal on held-out data (noise-free states) | 0 runs | " << t.worse << "/"
     << (t.with_effect + t.clean_runs) << " |\n"
     << "| median held-out 1-s RMSE reduction (noise-free states, in-library effects) | >= 50 % | " << b << " |\n"
     << "| an unexplained mismatch reported (with an effect) | - | " << pct(t.unexplained, t.with_effect) << " |\n"
     << "| a partial correction (with an effect; its effects are not counted as named) | - | "
     << pct(t.partial, t.with_effect) << " |\n"
     << "| a named effect and a substitute reported as ambiguous (with an effect) | - | "
     << pct(t.ambiguous, t.with_effect) << " |\n";
  if (t.errors) md << "\n" << t.errors << " run(s) failed (see the JSON lines' `error`).\n";
  return md.str();
}

std::string evidence_summary_json(const std::vector<EvidenceRun>& runs) {
  const Totals t = totals_of(runs);
  nlohmann::ordered_json j;
  j["runs_with_effect"] = t.with_effect;
  j["right"] = t.right;
  j["wrong"] = t.wrong;
  j["right_strict"] = t.right_strict;
  j["runs_with_a_place_effect_crossed_once"] = t.crossed_once;
  j["right_fraction"] = t.with_effect ? static_cast<double>(t.right) / t.with_effect : 0.0;
  j["wrong_fraction"] = t.with_effect ? static_cast<double>(t.wrong) / t.with_effect : 0.0;
  j["effect_free_runs"] = t.clean_runs;
  j["effect_free_named"] = t.clean_named;
  j["corrected_worse_than_nominal"] = t.worse;
  j["median_heldout_1s_rmse_reduction_clean"] = median(t.reductions);
  j["unexplained_reported"] = t.unexplained;
  j["partial_correction"] = t.partial;
  j["ambiguous_reported"] = t.ambiguous;
  j["errors"] = t.errors;
  nlohmann::ordered_json all = nlohmann::ordered_json::array();
  for (const auto& r : runs) all.push_back(nlohmann::ordered_json::parse(evidence_run_json(r)));
  j["runs"] = all;
  return j.dump(2);
}

}  // namespace mppi::diagnose
