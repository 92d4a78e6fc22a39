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
#include "diagnose/substitutes.hpp"

namespace mppi::diagnose {
using namespace selection;
namespace {

double heldout_1s_normalized_rmse(const ReplayModel& m, const PreparedRecording& d, const std::vector<char>& mask,
                                  const ReplayOptions& o) {
  return horizon_metrics(m, d, mask, {1.0}, 5, o)[0].normalized_rmse;
}

// One run of select_effects, stage by stage; the stages share the data, the candidates and what
// the earlier stages found.
class SelectionRun {
 public:
  SelectionRun(const PreparedRecording& d, const ModelFamily& nominal, const std::vector<char>& train_mask,
               const std::vector<char>& heldout_mask, const SelectionOptions& opt, const ReplayOptions& replay)
      : d_(d),
        nominal_(nominal),
        train_mask_(train_mask),
        heldout_mask_(heldout_mask),
        opt_(opt),
        replay_(replay),
        log_(&sel_.log, opt) {}

  Selection run() {
    make_problems(d_, nominal_, train_mask_, opt_, replay_, &problems_, log_);
    make_candidates(nominal_, opt_, &cands_, &members_, &joint_specs_);
    testable_pool();
    const auto nominal_model = nominal_.make({});
    held_nominal_ = heldout_1s_normalized_rmse(*nominal_model, d_, heldout_mask_, replay_);
    main_ = greedy(folds(), candidate_set(), pool_, opt_, problems_.n_eff, &log_);
    report_first_round();
    list_unidentified();
    count_stability();
    pick_dynamics_forms();
    std::vector<std::string> named = name_effects();
    find_substitutes_of(named);
    refit_named(named);
    if (!heldout_veto(named)) {
      state_verdict();
      if (opt_.withhold_substituted) mark_partial_where_substituted(substitutes_, &sel_);
    }
    return std::move(sel_);
  }

 private:
  Folds folds() const { return {problems_.fit, problems_.val, problems_.early_fit, problems_.early_val}; }
  CandidateSet candidate_set() const { return {cands_, members_}; }

  // Candidates this recording can identify at all (the rest are "not testable").
  void testable_pool() {
    const PreparedRecording& d = d_;
    const std::vector<char>& train_mask = train_mask_;
    std::vector<int>& pool = pool_;
    const ExcitationLevels excitation = measure_excitation(d, train_mask);
    sel_.candidates.resize(cands_.size());
    for (std::size_t i = 0; i < cands_.size(); ++i) {
      sel_.candidates[i].id = cands_[i]->id;
      if (members_[i].size() > 1)
        for (int m : members_[i]) sel_.candidates[i].joint_of.push_back(cands_[static_cast<std::size_t>(m)]->id);
      sel_.candidates[i].not_testable = excitation_shortfall(cands_[i]->needs, excitation);
      if (sel_.candidates[i].not_testable.empty())
        pool.push_back(static_cast<int>(i));
      else
        log_.push_back(cands_[i]->id + " not testable: " + sel_.candidates[i].not_testable);
    }
  }

  // Each candidate alone on the nominal model: its fit, validation, BIC and held-out figures.
  void report_first_round() {
    const double held_nominal = held_nominal_;
    for (const CandidateFit& c : main_.first_round) {
      CandidateReport& r = sel_.candidates[static_cast<std::size_t>(c.index)];
      r.params = c.fit.params;
      r.val_improvement = c.improvement;
      r.bic_delta = c.bic;
      const auto m = make_member_or_null(nominal_, c.fit.effects);
      r.heldout_improvement =
          m && held_nominal > 0 ? 1.0 - heldout_1s_normalized_rmse(*m, d_, heldout_mask_, replay_) / held_nominal : 0.0;
    }
  }

  // Listed as suspected (once, with the reason and the values it was fitted at).
  void suspect(int index, const std::string& reason, const EffectParams& e) {
    const EffectSpec& spec = *cands_[static_cast<std::size_t>(index)];
    for (const auto& s : sel_.suspected)
      if (s.id == spec.id) return;
    SuspectedEffect s{spec.id, reason, {}};
    for (const EffectParamSpec& p : spec.params) s.params.push_back({p.name, p.unit, e.*(p.member), 0.0});
    sel_.suspected.push_back(std::move(s));
  }

  // What passed with a parameter at its range's end and was not chosen later: suspected.
  void list_unidentified() {
    for (const auto& [index, reason] : main_.at_limit) {
      const bool chosen_later = std::find(main_.chosen.begin(), main_.chosen.end(), index) != main_.chosen.end();
      if (!chosen_later) {
        EffectParams e;
        for (const CandidateFit& c : main_.first_round)
          if (c.index == index) e = c.fit.effects;
        suspect(index, "not identifiable from this recording: " + reason, e);
      }
    }
  }

  // Stability selection over what passed: refits on block-bootstrap resamples of the fit part.
  void count_stability() {
    char line[512];
    std::vector<int>& stable_pool = stable_pool_;
    for (int i : main_.passed)
      if (std::none_of(main_.at_limit.begin(), main_.at_limit.end(), [&](const auto& a) { return a.first == i; }) ||
          std::find(main_.chosen.begin(), main_.chosen.end(), i) != main_.chosen.end())
        stable_pool.push_back(i);
    inclusion_.assign(cands_.size(), 0);
    if (!main_.chosen.empty() && opt_.stability_resamples > 0) {
      const std::vector<std::vector<int>> chosen = stability_resamples(folds(), candidate_set(), stable_pool, main_, opt_,
                                                                       problems_.n_eff, problems_.len, d_.dt_s);
      resample_choices_ = chosen;
      for (std::size_t b = 0; b < chosen.size(); ++b) {
        const std::vector<int>& c = chosen[b];
        const std::vector<std::string> ids = ids_of(cands_, c);
        std::string list;
        for (const auto& id : ids) list += (list.empty() ? "" : ", ") + id;
        log_.push_back("stability: the resample #" + std::to_string(b + 1) + " chose " +
                      (list.empty() ? "nothing" : list));
        for (int i : c) ++inclusion_[static_cast<std::size_t>(i)];
        std::vector<std::string> families;  // the actuators whose dynamics this resample chose
        for (int i : c) {
          const std::string& f = cands_[static_cast<std::size_t>(i)]->dynamics_of;
          if (!f.empty() && std::find(families.begin(), families.end(), f) == families.end()) families.push_back(f);
        }
        for (const auto& f : families) ++dynamics_inclusion_[f];
      }
      std::vector<int> reported;  // the library effects that the pool and the main_ selection stand for
      for (int i : stable_pool)
        for (int m : members_[static_cast<std::size_t>(i)])
          if (std::find(reported.begin(), reported.end(), m) == reported.end()) reported.push_back(m);
      for (int i : main_.chosen)
        if (std::find(reported.begin(), reported.end(), i) == reported.end()) reported.push_back(i);
      for (int i : reported) {
        CandidateReport& r = sel_.candidates[static_cast<std::size_t>(i)];
        r.inclusion_frequency = static_cast<double>(inclusion_[static_cast<std::size_t>(i)]) / opt_.stability_resamples;
        std::snprintf(line, sizeof line, "stability: %s chosen in %d of %d resamples", r.id.c_str(),
                      inclusion_[static_cast<std::size_t>(i)], opt_.stability_resamples);
        log_.push_back(line);
      }
    }
  }

  void pick_dynamics_forms() {
    char line[512];
    // One actuator's dynamics, in whichever form: where the resamples agree that the response of an
    // actuator is held back but split between its forms (a delay, a lag, a rate limit, a play: with
    // smooth commands their fits nearly coincide), the dynamics are stable and the form chosen most
    // often stands for them (on a tie, the one chosen on all the data); the other forms are listed as
    // suspected. Stability selection of groups of correlated variables works the same way.
    if (opt_.stability_resamples > 0 && !main_.chosen.empty())
      for (const auto& [family, count] : dynamics_inclusion_) {
        const double share = static_cast<double>(count) / opt_.stability_resamples;
        if (share < opt_.min_inclusion_frequency) continue;
        int pick = -1, pick_count = 0;
        for (std::size_t i = 0; i < cands_.size(); ++i) {
          if (cands_[i]->dynamics_of != family || inclusion_[i] == 0) continue;
          const bool on_all =
              std::find(main_.chosen.begin(), main_.chosen.end(), static_cast<int>(i)) != main_.chosen.end();
          if (inclusion_[i] > pick_count || (inclusion_[i] == pick_count && on_all)) {
            pick = static_cast<int>(i);
            pick_count = inclusion_[i];
          }
        }
        if (pick < 0 || static_cast<double>(pick_count) / opt_.stability_resamples >= opt_.min_inclusion_frequency)
          continue;
        family_pick_.push_back(pick);
        for (std::size_t i = 0; i < cands_.size(); ++i) {
          if (cands_[i]->dynamics_of != family || static_cast<int>(i) == pick || inclusion_[i] == 0) continue;
          std::snprintf(line, sizeof line,
                        "another form of the %s's dynamics, which are named as %s (chosen in %d of %d resamples, this "
                        "form in %d)",
                        family.c_str(), cands_[static_cast<std::size_t>(pick)]->id.c_str(), pick_count,
                        opt_.stability_resamples, inclusion_[i]);
          for (const CandidateFit& c : main_.first_round)
            if (c.index == static_cast<int>(i)) suspect(static_cast<int>(i), line, c.fit.effects);
        }
        std::snprintf(line, sizeof line,
                      "stable as the %s's dynamics: some form chosen in %d of %d resamples; named %s (%d of them)",
                      family.c_str(), count, opt_.stability_resamples, cands_[static_cast<std::size_t>(pick)]->id.c_str(),
                      pick_count);
        log_.push_back(line);
      }
  }

  // The effects named: chosen on all the data and stable, or chosen in enough of the resamples;
  // an actuator's dynamics as the form picked for them.
  std::vector<std::string> name_effects() {
    char line[512];
    auto in_family_pick = [&](int i) {
      return std::find(family_pick_.begin(), family_pick_.end(), i) != family_pick_.end();
    };
    std::vector<std::string> named;
    for (int i : main_.chosen) {
      const CandidateReport& r = sel_.candidates[static_cast<std::size_t>(i)];
      if (in_family_pick(i)) continue;  // named below, for its actuator's dynamics
      const std::string& family = cands_[static_cast<std::size_t>(i)]->dynamics_of;
      const auto stands_for = std::find_if(family_pick_.begin(), family_pick_.end(), [&](int p) {
        return !family.empty() && cands_[static_cast<std::size_t>(p)]->dynamics_of == family;
      });
      if (stands_for != family_pick_.end()) {
        std::snprintf(line, sizeof line, "another form of the %s's dynamics, which are named as %s", family.c_str(),
                      cands_[static_cast<std::size_t>(*stands_for)]->id.c_str());
        suspect(i, line, main_.effects);  // no-op where the family's own list above already has it
        continue;
      }
      if (opt_.stability_resamples > 0 && r.inclusion_frequency < opt_.min_inclusion_frequency) {
        std::snprintf(line, sizeof line, "unstable: chosen in %.0f %% of the resamples of the data (< %.0f %%)",
                      100 * r.inclusion_frequency, 100 * opt_.min_inclusion_frequency);
        suspect(i, line, main_.effects);
        continue;
      }
      named.push_back(r.id);
    }
    // Stability selection names what the resamples choose: an effect chosen in enough of them is
    // named even where the selection on all the data took a near rival in its place.
    if (opt_.stability_resamples > 0 && !main_.chosen.empty())
      for (std::size_t i = 0; i < cands_.size(); ++i) {
        const CandidateReport& r = sel_.candidates[i];
        if (!r.joint_of.empty() || r.inclusion_frequency < opt_.min_inclusion_frequency) continue;
        if (std::find(named.begin(), named.end(), r.id) != named.end()) continue;
        std::snprintf(line, sizeof line,
                      "stable: %s chosen in %.0f %% of the resamples, named though not chosen on all the data",
                      r.id.c_str(), 100 * r.inclusion_frequency);
        log_.push_back(line);
        named.push_back(r.id);
      }
    family_effects_ = main_.effects;  // the family picks' own first-round fits as start values
    for (int p : family_pick_) {
      named.push_back(cands_[static_cast<std::size_t>(p)]->id);
      for (const CandidateFit& c : main_.first_round)
        if (c.index == p)
          for (const EffectParamSpec& q : cands_[static_cast<std::size_t>(p)]->params)
            family_effects_.*(q.member) = c.fit.effects.*(q.member);
    }
    return named;
  }

  // The stability stage's substitutes (diagnose/substitutes.hpp) among the named effects.
  void find_substitutes_of(const std::vector<std::string>& named) {
    auto library_ids = [&](const std::vector<int>& chosen) {  // joint candidates as their members
      std::vector<std::string> ids;
      for (int c : chosen)
        for (int m : members_[static_cast<std::size_t>(c)]) ids.push_back(cands_[static_cast<std::size_t>(m)]->id);
      return ids;
    };
    std::vector<std::vector<std::string>> resamples;
    for (const auto& chosen : resample_choices_) resamples.push_back(library_ids(chosen));
    substitutes_ = find_substitutes(named, library_ids(main_.chosen), resamples, [&](const std::string& id) {
      for (const EffectSpec* c : cands_)
        if (c->id == id) return c->dynamics_of;
      return std::string();
    });
  }

  void refit_named(std::vector<std::string>& named) {
    const FitProblem& all = problems_.all;
    // Joint refit of the named effects on all training segments (parameters at a bound held at
    // their nominal value, or the effect dropped: diagnose/joint_refit.hpp).
    if (!named.empty()) {
      const EffectParams start = joint_refit_start(main_.rounds, ids_of(cands_, main_.chosen), named, family_effects_);
      const JointRefit joint = refit_named_jointly(all, named, only(named, start), opt_.range_limit_margin);
      for (const auto& l : joint.log) log_.push_back(l);
      for (const auto& [id, why] : joint.not_identified)
        for (std::size_t i = 0; i < cands_.size(); ++i)
          if (cands_[i]->id == id)
            suspect(static_cast<int>(i), "not identifiable from this recording: " + why, joint.effects);
      named = joint.kept;
      sel_.final_effects = joint.effects;
      for (const auto& id : named) {  // a change time was searched over the data: its value and spread
        const EffectSpec& s = effect_spec(id);
        if (s.data_grid != DataGrid::kTime) continue;
        sel_.final_params.push_back({s.params[0].name, s.params[0].unit, joint.effects.*(s.params[0].member), 0.0});
        for (const auto& c : sel_.candidates)
          if (c.id == id && !c.params.empty()) sel_.final_params.back().stddev = c.params[0].stddev;
      }
      sel_.final_params.insert(sel_.final_params.end(), joint.params.begin(), joint.params.end());
    }
    sel_.selected = named;
    for (auto& c : sel_.candidates) {
      c.selected = std::find(named.begin(), named.end(), c.id) != named.end();
      if (c.selected)
        for (std::size_t k = 0; k < main_.chosen.size(); ++k)
          if (cands_[static_cast<std::size_t>(main_.chosen[k])]->id == c.id) c.round_selected = static_cast<int>(k) + 1;
    }
  }

  // The held-out part decides whether the correction is trusted; false: it is not (the verdict
  // says so and nothing is named).
  bool heldout_veto(const std::vector<std::string>& named) {
    const PreparedRecording& d = d_;
    const double held_nominal = held_nominal_;
    char line[512];
    sel_.heldout_nominal = held_nominal;
    sel_.heldout_corrected = held_nominal;
    if (!named.empty()) {
      const auto corrected = make_member_or_null(nominal_, sel_.final_effects);
      sel_.heldout_corrected = corrected ? heldout_1s_normalized_rmse(*corrected, d_, heldout_mask_, replay_)
                                        : std::numeric_limits<double>::infinity();
      const int held_starts = static_cast<int>(
          make_segments(d, heldout_mask_, std::max(1, static_cast<int>(std::lround(1.0 / d.dt_s))), 5).size());
      if (held_starts > 0 && !(sel_.heldout_corrected < held_nominal)) {
        std::snprintf(line, sizeof line,
                      "the corrected model is not better on the held-out part (1-s normalised RMSE %.4f -> %.4f)",
                      held_nominal, sel_.heldout_corrected);
        for (const auto& id : named)
          for (std::size_t i = 0; i < cands_.size(); ++i)
            if (cands_[i]->id == id) suspect(static_cast<int>(i), line, sel_.final_effects);
        for (auto& c : sel_.candidates) c.selected = false;
        sel_.reliable = false;
        sel_.selected.clear();
        sel_.final_effects = {};
        sel_.final_params.clear();
        sel_.verdict = std::string("no reliable correction: ") + line;
        log_.push_back(sel_.verdict);
        return true;
      }
    }
    return false;
  }

  void state_verdict() {
    if (sel_.selected.empty())
      sel_.verdict = sel_.suspected.empty()
                        ? "nothing named: the nominal model stands"
                        : "nothing named; suspected effects listed, not identifiable from this recording";
    else
      sel_.verdict = "named: " + [&] {
        std::string s;
        for (const auto& id : sel_.selected) s += (s.empty() ? "" : ", ") + id;
        return s;
      }();
    log_.push_back(sel_.verdict);
  }

  const PreparedRecording& d_;
  const ModelFamily& nominal_;
  const std::vector<char>& train_mask_;
  const std::vector<char>& heldout_mask_;
  const SelectionOptions& opt_;
  const ReplayOptions& replay_;
  Selection sel_;
  SelectionLog log_;
  Problems problems_;
  std::vector<const EffectSpec*> cands_;
  Members members_;
  std::deque<EffectSpec> joint_specs_;
  std::vector<int> pool_, stable_pool_;
  double held_nominal_ = 0;
  GreedyResult main_;
  std::vector<int> inclusion_;                     // resamples that chose each candidate
  std::vector<std::vector<int>> resample_choices_;  // what each resample chose (candidate indices)
  std::vector<SubstitutePair> substitutes_;         // named effects with a rival in the resamples
  std::map<std::string, int> dynamics_inclusion_;  // resamples that chose some form of an actuator's dynamics
  std::vector<int> family_pick_;                   // candidates named for their actuator's dynamics
  EffectParams family_effects_;                   // the family picks' own first-round fits as start values
};

}  // namespace

Selection select_effects(const PreparedRecording& d, const ModelFamily& nominal, const std::vector<char>& train_mask,
                         const std::vector<char>& heldout_mask, const SelectionOptions& opt,
                         const ReplayOptions& replay) {
  return SelectionRun(d, nominal, train_mask, heldout_mask, opt, replay).run();
}

}  // namespace mppi::diagnose
