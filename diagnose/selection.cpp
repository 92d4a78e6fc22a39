// Which effects to name: greedy forward selection judged on later data (forward validation),
// checked for identifiability (excitation, parameters at their search range's end), for
// stability (block-bootstrap refits) and, at the end, on the held-out part of the recording.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <map>

#include "base/error.hpp"
#include "diagnose/fit.hpp"
#include "diagnose/identifiability.hpp"
#include "diagnose/joint_refit.hpp"
#include "diagnose/selection_stages.hpp"

namespace mppi::diagnose {
using namespace selection;
namespace {

double heldout_1s_normalized_rmse(const ReplayModel& m, const DiagData& d, const std::vector<char>& mask,
                                  const ReplayOptions& o) {
  return horizon_metrics(m, d, mask, {1.0}, 5, o)[0].normalized_rmse;
}

// The training rows as fit problems: all segments, the fit part and the later block that
// validates it, and the earlier fold (the fit part's halves).
struct Problems {
  FitProblem all, fit, val, early_fit, early_val;
  int len = 0;       // rows per segment
  double n_eff = 0;  // the fit part's effective sample count (the BIC's)
};

void make_problems(const DiagData& d, const ModelFamily& nominal, const std::vector<char>& train_mask,
                   const SelectionOptions& opt, const ReplayOptions& replay, Problems* p, SelectionLog& log) {
  FitProblem& all = p->all;
  FitProblem& fit = p->fit;
  FitProblem& val = p->val;
  const int len = p->len = std::max(2, static_cast<int>(std::lround(opt.fit_horizon_s / d.dt_s)));
  const auto segs = make_segments(d, train_mask, len, len);
  if (segs.size() < 6)
    throw Error(d.source + ": too little continuous training data: " + std::to_string(segs.size()) +
                " segments of " + std::to_string(opt.fit_horizon_s) + " s (need >= 6)");
  all.data = fit.data = val.data = &d;
  all.family = fit.family = val.family = &nominal;
  all.replay = fit.replay = val.replay = replay;
  all.scale = fit.scale = val.scale = channel_scales(d, train_mask);
  all.segments = segs;
  // Forward validation: segments are in time order; the last part judges the earlier.
  const std::size_t n_val = std::clamp<std::size_t>(
      static_cast<std::size_t>(std::lround(opt.validation_fraction * static_cast<double>(segs.size()))), 3,
      segs.size() - 3);
  fit.segments.assign(segs.begin(), segs.end() - static_cast<std::ptrdiff_t>(n_val));
  val.segments.assign(segs.end() - static_cast<std::ptrdiff_t>(n_val), segs.end());
  FitProblem& early_fit = p->early_fit;
  FitProblem& early_val = p->early_val;
  early_fit = fit;
  early_val = fit;
  const std::size_t half = fit.segments.size() / 2;
  early_fit.segments.assign(fit.segments.begin(), fit.segments.begin() + static_cast<std::ptrdiff_t>(half));
  early_val.segments.assign(fit.segments.begin() + static_cast<std::ptrdiff_t>(half), fit.segments.end());
  if (early_fit.segments.size() < 3 || early_val.segments.size() < 3) early_val.segments.clear();
  const double n_fit = static_cast<double>(fit.segments.size() * static_cast<std::size_t>(len) * kChannels);
  p->n_eff = n_fit / opt.samples_per_independent;
  char line[512];
  std::snprintf(line, sizeof line, "fit on %zu segments of %.2f s up to t = %.1f s, validated on the %zu after",
                fit.segments.size(), len * d.dt_s, d.t[fit.segments.back().start], val.segments.size());
  log.push_back(line);
}

// The candidates: the library's (or those asked for) that the nominal model takes, then the joint
// ones of partner terms. joint_specs holds the joint candidates' specs (stable addresses).
void make_candidates(const ModelFamily& nominal, const SelectionOptions& opt, std::vector<const EffectSpec*>* out,
                     Members* members_out, std::deque<EffectSpec>* joint_specs) {
  std::vector<const EffectSpec*>& cands = *out;
  Members& members = *members_out;
  if (opt.candidates.empty()) {
    for (const auto& e : effect_library())
      if (nominal.supports(e.id)) cands.push_back(&e);
  } else {
    for (const auto& id : opt.candidates) {
      if (!nominal.supports(id))
        throw Error("effect '" + id + "' needs a tyre model; the nominal " + nominal.name() + " has none");
      cands.push_back(&effect_spec(id));
    }
  }
  // Partner terms are also fitted together, as one joint candidate: a steering map's gain and
  // trim, a throttle map's gain and offset, and an ESC's neutral (the motor freewheeling, no
  // back-EMF braking, and a drag brake instead). Where both are wrong, each alone takes up part of
  // the other's error and can fail where the two together explain the data.
  members.assign(cands.size(), {});
  for (std::size_t i = 0; i < cands.size(); ++i) members[i] = {static_cast<int>(i)};
  static const std::pair<const char*, const char*> kPartners[] = {{"steer_gain", "steer_offset"},
                                                                   {"throttle_gain", "throttle_offset"},
                                                                   {"motor_freewheel", "drag_brake"}};
  for (const auto& [a, b] : kPartners) {
    int ia = -1, ib = -1;
    for (std::size_t i = 0; i < cands.size(); ++i) {
      if (cands[i]->id == a) ia = static_cast<int>(i);
      if (cands[i]->id == b) ib = static_cast<int>(i);
    }
    if (ia < 0 || ib < 0) continue;
    EffectSpec joint = *cands[static_cast<std::size_t>(ia)];
    joint.id = std::string(a) + "+" + b;
    joint.description = "joint: " + joint.description + "; " + cands[static_cast<std::size_t>(ib)]->description;
    const auto& more = cands[static_cast<std::size_t>(ib)]->params;
    joint.params.insert(joint.params.end(), more.begin(), more.end());
    joint_specs->push_back(std::move(joint));
    cands.push_back(&joint_specs->back());
    members.push_back({ia, ib});
  }
}

}  // namespace

Selection select_effects(const DiagData& d, const ModelFamily& nominal, const std::vector<char>& train_mask,
                         const std::vector<char>& heldout_mask, const SelectionOptions& opt,
                         const ReplayOptions& replay) {
  Selection sel;
  SelectionLog log(&sel.log, opt);
  Problems problems;
  make_problems(d, nominal, train_mask, opt, replay, &problems, log);
  const FitProblem& all = problems.all;
  const FitProblem& fit = problems.fit;
  const FitProblem& val = problems.val;
  const FitProblem& early_fit = problems.early_fit;
  const FitProblem& early_val = problems.early_val;
  const int len = problems.len;
  const double n_eff = problems.n_eff;
  char line[512];

  // Candidates, and which of them this recording can identify at all.
  std::vector<const EffectSpec*> cands;
  Members members;
  std::deque<EffectSpec> joint_specs;
  make_candidates(nominal, opt, &cands, &members, &joint_specs);
  const ExcitationLevels excitation = measure_excitation(d, train_mask);
  sel.candidates.resize(cands.size());
  std::vector<int> pool;
  for (std::size_t i = 0; i < cands.size(); ++i) {
    sel.candidates[i].id = cands[i]->id;
    if (members[i].size() > 1)
      for (int m : members[i]) sel.candidates[i].joint_of.push_back(cands[static_cast<std::size_t>(m)]->id);
    sel.candidates[i].not_testable = excitation_shortfall(cands[i]->needs, excitation);
    if (sel.candidates[i].not_testable.empty())
      pool.push_back(static_cast<int>(i));
    else
      log.push_back(cands[i]->id + " not testable: " + sel.candidates[i].not_testable);
  }

  const auto nominal_model = nominal.make({});
  const double held_nominal = heldout_1s_normalized_rmse(*nominal_model, d, heldout_mask, replay);
  const Folds folds{fit, val, early_fit, early_val};
  const CandidateSet candidate_set{cands, members};
  const GreedyResult main = greedy(folds, candidate_set, pool, opt, n_eff, &log);
  for (const CandidateFit& c : main.first_round) {
    CandidateReport& r = sel.candidates[static_cast<std::size_t>(c.index)];
    r.params = c.fit.params;
    r.val_improvement = c.improvement;
    r.bic_delta = c.bic;
    const auto m = make_member_or_null(nominal, c.fit.effects);
    r.heldout_improvement = m && held_nominal > 0 ? 1.0 - heldout_1s_normalized_rmse(*m, d, heldout_mask, replay) / held_nominal : 0.0;
  }
  auto suspect = [&](int index, const std::string& reason, const EffectParams& e) {
    const EffectSpec& spec = *cands[static_cast<std::size_t>(index)];
    for (const auto& s : sel.suspected)
      if (s.id == spec.id) return;
    SuspectedEffect s{spec.id, reason, {}};
    for (const EffectParamSpec& p : spec.params) s.params.push_back({p.name, p.unit, e.*(p.member), 0.0});
    sel.suspected.push_back(std::move(s));
  };
  for (const auto& [index, reason] : main.at_limit) {
    const bool chosen_later = std::find(main.chosen.begin(), main.chosen.end(), index) != main.chosen.end();
    if (!chosen_later) {
      EffectParams e;
      for (const CandidateFit& c : main.first_round)
        if (c.index == index) e = c.fit.effects;
      suspect(index, "not identifiable from this recording: " + reason, e);
    }
  }

  // Stability selection over what passed: refits on block-bootstrap resamples of the fit part.
  std::vector<int> stable_pool;
  for (int i : main.passed)
    if (std::none_of(main.at_limit.begin(), main.at_limit.end(), [&](const auto& a) { return a.first == i; }) ||
        std::find(main.chosen.begin(), main.chosen.end(), i) != main.chosen.end())
      stable_pool.push_back(i);
  std::vector<int> inclusion(cands.size(), 0);
  std::map<std::string, int> dynamics_inclusion;  // resamples that chose some form of an actuator's dynamics
  if (!main.chosen.empty() && opt.stability_resamples > 0) {
    const std::vector<std::vector<int>> chosen =
        stability_resamples(folds, candidate_set, stable_pool, main, opt, n_eff, len, d.dt_s);
    for (std::size_t b = 0; b < chosen.size(); ++b) {
      const std::vector<int>& c = chosen[b];
      const std::vector<std::string> ids = ids_of(cands, c);
      std::string list;
      for (const auto& id : ids) list += (list.empty() ? "" : ", ") + id;
      log.push_back("stability: the resample #" + std::to_string(b + 1) + " chose " + (list.empty() ? "nothing" : list));
      for (int i : c) ++inclusion[static_cast<std::size_t>(i)];
      std::vector<std::string> families;  // the actuators whose dynamics this resample chose
      for (int i : c) {
        const std::string& f = cands[static_cast<std::size_t>(i)]->dynamics_of;
        if (!f.empty() && std::find(families.begin(), families.end(), f) == families.end()) families.push_back(f);
      }
      for (const auto& f : families) ++dynamics_inclusion[f];
    }
    std::vector<int> reported;  // the library effects that the pool and the main selection stand for
    for (int i : stable_pool)
      for (int m : members[static_cast<std::size_t>(i)])
        if (std::find(reported.begin(), reported.end(), m) == reported.end()) reported.push_back(m);
    for (int i : main.chosen)
      if (std::find(reported.begin(), reported.end(), i) == reported.end()) reported.push_back(i);
    for (int i : reported) {
      CandidateReport& r = sel.candidates[static_cast<std::size_t>(i)];
      r.inclusion_frequency = static_cast<double>(inclusion[static_cast<std::size_t>(i)]) / opt.stability_resamples;
      std::snprintf(line, sizeof line, "stability: %s chosen in %d of %d resamples", r.id.c_str(),
                    inclusion[static_cast<std::size_t>(i)], opt.stability_resamples);
      log.push_back(line);
    }
  }
  // One actuator's dynamics, in whichever form: where the resamples agree that the response of an
  // actuator is held back but split between its forms (a delay, a lag, a rate limit, a play: with
  // smooth commands their fits nearly coincide), the dynamics are stable and the form chosen most
  // often stands for them (on a tie, the one chosen on all the data); the other forms are listed as
  // suspected. Stability selection of groups of correlated variables works the same way.
  std::vector<int> family_pick;  // candidates named for their actuator's dynamics
  if (opt.stability_resamples > 0 && !main.chosen.empty())
    for (const auto& [family, count] : dynamics_inclusion) {
      const double share = static_cast<double>(count) / opt.stability_resamples;
      if (share < opt.min_inclusion_frequency) continue;
      int pick = -1, pick_count = 0;
      for (std::size_t i = 0; i < cands.size(); ++i) {
        if (cands[i]->dynamics_of != family || inclusion[i] == 0) continue;
        const bool on_all = std::find(main.chosen.begin(), main.chosen.end(), static_cast<int>(i)) != main.chosen.end();
        if (inclusion[i] > pick_count || (inclusion[i] == pick_count && on_all)) {
          pick = static_cast<int>(i);
          pick_count = inclusion[i];
        }
      }
      if (pick < 0 || static_cast<double>(pick_count) / opt.stability_resamples >= opt.min_inclusion_frequency) continue;
      family_pick.push_back(pick);
      for (std::size_t i = 0; i < cands.size(); ++i) {
        if (cands[i]->dynamics_of != family || static_cast<int>(i) == pick || inclusion[i] == 0) continue;
        std::snprintf(line, sizeof line, "another form of the %s's dynamics, which are named as %s (chosen in %d of %d resamples, this form in %d)",
                      family.c_str(), cands[static_cast<std::size_t>(pick)]->id.c_str(), pick_count, opt.stability_resamples, inclusion[i]);
        for (const CandidateFit& c : main.first_round)
          if (c.index == static_cast<int>(i)) suspect(static_cast<int>(i), line, c.fit.effects);
      }
      std::snprintf(line, sizeof line, "stable as the %s's dynamics: some form chosen in %d of %d resamples; named %s (%d of them)",
                    family.c_str(), count, opt.stability_resamples, cands[static_cast<std::size_t>(pick)]->id.c_str(), pick_count);
      log.push_back(line);
    }
  auto in_family_pick = [&](int i) { return std::find(family_pick.begin(), family_pick.end(), i) != family_pick.end(); };
  std::vector<std::string> named;
  for (int i : main.chosen) {
    const CandidateReport& r = sel.candidates[static_cast<std::size_t>(i)];
    if (in_family_pick(i)) continue;  // named below, for its actuator's dynamics
    const std::string& family = cands[static_cast<std::size_t>(i)]->dynamics_of;
    const auto stands_for = std::find_if(family_pick.begin(), family_pick.end(), [&](int p) {
      return !family.empty() && cands[static_cast<std::size_t>(p)]->dynamics_of == family;
    });
    if (stands_for != family_pick.end()) {
      std::snprintf(line, sizeof line, "another form of the %s's dynamics, which are named as %s",
                    family.c_str(), cands[static_cast<std::size_t>(*stands_for)]->id.c_str());
      suspect(i, line, main.effects);  // no-op where the family's own list above already has it
      continue;
    }
    if (opt.stability_resamples > 0 && r.inclusion_frequency < opt.min_inclusion_frequency) {
      std::snprintf(line, sizeof line, "unstable: chosen in %.0f %% of the resamples of the data (< %.0f %%)",
                    100 * r.inclusion_frequency, 100 * opt.min_inclusion_frequency);
      suspect(i, line, main.effects);
      continue;
    }
    named.push_back(r.id);
  }
  // Stability selection names what the resamples choose: an effect chosen in enough of them is
  // named even where the selection on all the data took a near rival in its place.
  if (opt.stability_resamples > 0 && !main.chosen.empty())
    for (std::size_t i = 0; i < cands.size(); ++i) {
      const CandidateReport& r = sel.candidates[i];
      if (!r.joint_of.empty() || r.inclusion_frequency < opt.min_inclusion_frequency) continue;
      if (std::find(named.begin(), named.end(), r.id) != named.end()) continue;
      std::snprintf(line, sizeof line, "stable: %s chosen in %.0f %% of the resamples, named though not chosen on all the data",
                    r.id.c_str(), 100 * r.inclusion_frequency);
      log.push_back(line);
      named.push_back(r.id);
    }
  EffectParams family_effects = main.effects;  // the family picks' own first-round fits as start values
  for (int p : family_pick) {
    named.push_back(cands[static_cast<std::size_t>(p)]->id);
    for (const CandidateFit& c : main.first_round)
      if (c.index == p)
        for (const EffectParamSpec& q : cands[static_cast<std::size_t>(p)]->params) family_effects.*(q.member) = c.fit.effects.*(q.member);
  }

  // Joint refit of the named effects on all training segments (parameters at a bound held at
  // their nominal value, or the effect dropped: diagnose/joint_refit.hpp).
  if (!named.empty()) {
    const EffectParams start = joint_refit_start(main.rounds, ids_of(cands, main.chosen), named, family_effects);
    const JointRefit joint = refit_named_jointly(all, named, only(named, start), opt.range_limit_margin);
    for (const auto& l : joint.log) log.push_back(l);
    for (const auto& [id, why] : joint.not_identified)
      for (std::size_t i = 0; i < cands.size(); ++i)
        if (cands[i]->id == id) suspect(static_cast<int>(i), "not identifiable from this recording: " + why, joint.effects);
    named = joint.kept;
    sel.final_effects = joint.effects;
    for (const auto& id : named) {  // a change time was searched over the data: its value and spread
      const EffectSpec& s = effect_spec(id);
      if (s.data_grid != DataGrid::kTime) continue;
      sel.final_params.push_back({s.params[0].name, s.params[0].unit, joint.effects.*(s.params[0].member), 0.0});
      for (const auto& c : sel.candidates)
        if (c.id == id && !c.params.empty()) sel.final_params.back().stddev = c.params[0].stddev;
    }
    sel.final_params.insert(sel.final_params.end(), joint.params.begin(), joint.params.end());
  }
  sel.selected = named;
  for (auto& c : sel.candidates) {
    c.selected = std::find(named.begin(), named.end(), c.id) != named.end();
    if (c.selected)
      for (std::size_t k = 0; k < main.chosen.size(); ++k)
        if (cands[static_cast<std::size_t>(main.chosen[k])]->id == c.id) c.round_selected = static_cast<int>(k) + 1;
  }

  // The held-out part decides whether the correction is trusted.
  sel.heldout_nominal = held_nominal;
  sel.heldout_corrected = held_nominal;
  if (!named.empty()) {
    const auto corrected = make_member_or_null(nominal, sel.final_effects);
    sel.heldout_corrected = corrected ? heldout_1s_normalized_rmse(*corrected, d, heldout_mask, replay)
                                      : std::numeric_limits<double>::infinity();
    const int held_starts = static_cast<int>(make_segments(d, heldout_mask, std::max(1, static_cast<int>(std::lround(1.0 / d.dt_s))), 5).size());
    if (held_starts > 0 && !(sel.heldout_corrected < held_nominal)) {
      std::snprintf(line, sizeof line, "the corrected model is not better on the held-out part (1-s normalised RMSE %.4f -> %.4f)",
                    held_nominal, sel.heldout_corrected);
      for (const auto& id : named)
        for (std::size_t i = 0; i < cands.size(); ++i)
          if (cands[i]->id == id) suspect(static_cast<int>(i), line, sel.final_effects);
      for (auto& c : sel.candidates) c.selected = false;
      sel.reliable = false;
      sel.selected.clear();
      sel.final_effects = {};
      sel.final_params.clear();
      sel.verdict = std::string("no reliable correction: ") + line;
      log.push_back(sel.verdict);
      return sel;
    }
  }
  if (sel.selected.empty())
    sel.verdict = sel.suspected.empty() ? "nothing named: the nominal model stands"
                                        : "nothing named; suspected effects listed, not identifiable from this recording";
  else
    sel.verdict = "named: " + [&] {
      std::string s;
      for (const auto& id : sel.selected) s += (s.empty() ? "" : ", ") + id;
      return s;
    }();
  log.push_back(sel.verdict);
  return sel;
}

}  // namespace mppi::diagnose
