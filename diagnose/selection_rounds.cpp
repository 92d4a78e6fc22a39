// The forward rounds of the selection (selection_stages.hpp): fit every remaining candidate on
// top of what is chosen, judge it on later data, rank what passes, take the first identified one,
// refit the chosen together; then backward elimination and the re-try of an actuator's dynamics
// forms.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include <tbb/parallel_for.h>

#include "diagnose/identifiability.hpp"
#include "diagnose/ranking.hpp"
#include "diagnose/selection_stages.hpp"

namespace mppi::diagnose::selection {

std::vector<ParamSpec> joint_free_params(const std::vector<const EffectSpec*>& cands, const std::vector<int>& chosen,
                                         const EffectParams& at) {
  std::vector<ParamSpec> free;
  for (int i : chosen) {
    const EffectSpec& s = *cands[static_cast<std::size_t>(i)];
    for (const ParamSpec& q : active_params(s, at))
      if (!(s.data_grid == DataGrid::kTime && q.member == s.params[0].member)) free.push_back(q);
  }
  return free;
}

EffectParams only(const std::vector<std::string>& ids, const EffectParams& from) {
  EffectParams e;
  for (const auto& id : ids)
    for (const EffectParamSpec& p : effect_spec(id).params) e.*(p.member) = from.*(p.member);
  return e;
}

std::vector<std::string> ids_of(const std::vector<const EffectSpec*>& cands, const std::vector<int>& chosen) {
  std::vector<std::string> ids;
  for (int i : chosen) ids.push_back(cands[static_cast<std::size_t>(i)]->id);
  return ids;
}

namespace {

// What the rounds have arrived at: the chosen effects' values, and their costs on both blocks.
struct Chosen {
  EffectParams base;
  double fit_cost = 0, val_cost = 0;
};

// One candidate on top of `at`: fitted on the fit part, judged on the later block (and, where
// that block cannot judge it, on the earlier fold).
CandidateFit fit_candidate(const Folds& folds, const CandidateSet& cands, int i, const Chosen& at,
                           const SelectionOptions& opt, double n_eff, const std::vector<CandidateFit>* place_starts) {
  const EffectSpec& spec = cands[i];
  CandidateFit c;
  c.index = i;
  c.fit = fit_effect(folds.fit, at.base, spec);
  if (place_starts && spec.data_grid == DataGrid::kPlace)
    for (const CandidateFit& s : *place_starts)
      if (s.index == i) {
        FitResult from_main = fit_place_effect_from(folds.fit, at.base, spec, s.fit.effects);
        // An identified fit is preferred to one with a parameter at its range's end (a third
        // patch of all the data grown to the largest radius on a resample's fewer passes).
        const bool main_identified = range_limit_shortfall(spec, from_main.effects, opt.range_limit_margin).empty();
        const bool search_identified = range_limit_shortfall(spec, c.fit.effects, opt.range_limit_margin).empty();
        if (main_identified != search_identified ? main_identified : from_main.cost < c.fit.cost)
          c.fit = std::move(from_main);
      }
  c.val_cost = mean_cost(folds.val, c.fit.effects);
  const double k = static_cast<double>(spec.params.size());
  c.bic = n_eff * std::log(c.fit.cost / at.fit_cost) + k * std::log(n_eff);
  c.improvement = 1.0 - c.val_cost / at.val_cost;
  c.passes = c.improvement >= opt.min_val_improvement && c.bic <= -opt.min_bic_drop && c.val_cost < at.val_cost;
  if (!c.passes && c.bic <= -opt.min_bic_drop && c.improvement >= 0.0 && c.improvement < opt.inconclusive_share &&
      !folds.early_val.segments.empty()) {
    const FitResult early = fit_effect(folds.early_fit, at.base, spec);
    const double early_base = mean_cost(folds.early_val, at.base);
    const double early_improvement = early_base > 0 ? 1.0 - mean_cost(folds.early_val, early.effects) / early_base : 0.0;
    char note[96];
    std::snprintf(note, sizeof note, " (later block inconclusive; earlier fold %+.1f %%)", 100 * early_improvement);
    c.earlier_fold = note;
    if (early_improvement >= opt.min_val_improvement) {
      c.improvement = early_improvement;
      c.passes = true;
      c.judged_early = true;
    }
  }
  return c;
}

// The candidates that pass, best first. Improvements on different blocks do not compare: what
// passed on the later block (the main fold) is ranked; what passed only on the earlier fold is
// considered when nothing else passes.
std::vector<const CandidateFit*> rank_round(const std::vector<CandidateFit>& tried, const CandidateSet& cands,
                                            const SelectionOptions& opt) {
  std::vector<const CandidateFit*> order;
  for (const auto& c : tried)
    if (c.passes && !c.judged_early) order.push_back(&c);
  if (order.empty())
    for (const auto& c : tried)
      if (c.passes) order.push_back(&c);
  if (order.empty()) return order;
  std::vector<RankedCandidate> ranked;
  for (const CandidateFit* c : order) ranked.push_back({c->improvement, c->bic, used_param_count(cands[c->index], c->fit)});
  const std::vector<const CandidateFit*> unranked = order;
  const std::vector<std::size_t> rank = rank_passing_candidates(ranked, opt.parsimony_share, opt.strong_bic_evidence);
  for (std::size_t k = 0; k < rank.size(); ++k) order[k] = unranked[rank[k]];
  // What the recording declares comes first: where the throttle column is a speed command, the
  // speed loop (when it passes) is the model's structure and the others compete on top of it. A
  // drive term that mimics the loop's feedforward (the motor's no-load speed scaled to V / v_nl)
  // would otherwise win on simplicity and take its place.
  const auto declared = std::find_if(order.begin(), order.end(), [&](const CandidateFit* c) {
    return cands[c->index].needs == Excitation::kSpeedCommand;
  });
  if (declared != order.end()) std::rotate(order.begin(), declared, declared + 1);
  return order;
}

// The first ranked candidate whose parameters are identified and that no clock-free candidate
// explains as well; nullptr if none. Those passed over are logged (and the unidentified listed).
const CandidateFit* pick_candidate(const std::vector<const CandidateFit*>& order, const std::vector<CandidateFit>& tried,
                                   const CandidateSet& cands, const SelectionOptions& opt, int round,
                                   GreedyResult& out, SelectionLog* log) {
  const std::string prefix = "round " + std::to_string(round) + ": ";
  for (const CandidateFit* c : order) {
    const EffectSpec& spec = cands[c->index];
    const std::string limit = range_limit_shortfall(spec, c->fit.effects, opt.range_limit_margin);
    if (!limit.empty()) {
      out.at_limit.emplace_back(c->index, limit);
      if (log) log->push_back(prefix + spec.id + " not identified: " + limit);
      continue;
    }
    if (spec.data_grid == DataGrid::kTime) {
      // A change "from time t on" is also what a place or a state that the car reaches later
      // looks like; the state-dependent explanation wins when it does nearly as well.
      const CandidateFit* rival = nullptr;
      for (const auto& o : tried) {
        const EffectSpec& os = cands[o.index];
        if (os.data_grid == DataGrid::kTime || os.hook != EffectHook::kChassis) continue;
        if (o.improvement >= opt.time_change_dominance * c->improvement && (!rival || o.improvement > rival->improvement))
          rival = &o;
      }
      if (rival) {
        if (log) log->push_back(prefix + spec.id + " set aside: " + cands[rival->index].id + " explains it as well without a clock");
        continue;
      }
    }
    return c;
  }
  return nullptr;
}

// One forward round: every candidate of the pool not yet taken, fitted in parallel (each on its
// own copy of the model); the log and the ranking then go through them in pool order, so the
// result does not depend on the number of threads. Returns what it picked (nullptr: stop).
std::optional<CandidateFit> forward_round(const Folds& folds, const CandidateSet& cands, const std::vector<int>& pool,
                                          const std::vector<bool>& taken, const Chosen& at, int round,
                                          const SelectionOptions& opt, double n_eff, GreedyResult& out, SelectionLog* log,
                                          const std::vector<CandidateFit>* place_starts) {
  std::vector<int> todo;
  for (int i : pool)
    if (!taken[static_cast<std::size_t>(i)]) todo.push_back(i);
  std::vector<CandidateFit> tried(todo.size());
  tbb::parallel_for(std::size_t(0), todo.size(), [&](std::size_t n) {
    tried[n] = fit_candidate(folds, cands, todo[n], at, opt, n_eff, place_starts);
  });
  char line[512];
  for (const CandidateFit& c : tried) {
    if (log) {
      std::snprintf(line, sizeof line, "round %d: %-20s validation %+6.1f %%, dBIC %+9.1f%s%s", round,
                    cands[c.index].id.c_str(), 100 * (1.0 - c.val_cost / at.val_cost), c.bic, c.earlier_fold.c_str(),
                    c.passes ? "  passes" : "");
      log->push_back(line);
    }
    if (c.passes && std::find(out.passed.begin(), out.passed.end(), c.index) == out.passed.end())
      out.passed.push_back(c.index);
  }
  if (round == 1) out.first_round = tried;
  const CandidateFit* pick = pick_candidate(rank_round(tried, cands, opt), tried, cands, opt, round, out, log);
  if (!pick) {
    if (log) log->push_back("round " + std::to_string(round) + ": no candidate passes; stop");
    return std::nullopt;
  }
  return *pick;
}

// Takes the picked candidate (a joint candidate as its partners; a chosen effect takes the joint
// candidates it is in), then refits everything chosen together, so that the next round does not
// pick an effect only because it makes up for an earlier one's bias.
void take(const Folds& folds, const CandidateSet& cands, const CandidateFit& pick, int round, std::vector<bool>& taken,
          GreedyResult& out, Chosen& at, SelectionLog* log) {
  const std::vector<int>& picked = cands.members[static_cast<std::size_t>(pick.index)];
  for (std::size_t j = 0; j < cands.specs.size(); ++j)
    for (int m : cands.members[j])
      if (std::find(picked.begin(), picked.end(), m) != picked.end()) taken[j] = true;
  out.chosen.insert(out.chosen.end(), picked.begin(), picked.end());
  at = {pick.fit.effects, pick.fit.cost, pick.val_cost};
  if (log) {
    char line[512];
    std::snprintf(line, sizeof line, "round %d: selected %s (validation %+.1f %%, dBIC %.1f)", round,
                  cands[pick.index].id.c_str(), 100 * pick.improvement, pick.bic);
    log->push_back(line);
  }
  if (out.chosen.size() > 1) {
    const FitResult joint = fit_params(folds.fit, at.base, joint_free_params(cands.specs, out.chosen, at.base));
    if (joint.cost <= at.fit_cost) at = {joint.effects, joint.cost, mean_cost(folds.val, joint.effects)};
  }
  out.rounds.push_back({ids_of(cands.specs, out.chosen), at.base});
}

// Backward elimination: an effect whose removal (the others refitted together) costs less than
// the improvement a new effect must bring on the validation data was made redundant by a later one.
void backward_eliminate(const Folds& folds, const CandidateSet& cands, const SelectionOptions& opt, GreedyResult& out,
                        Chosen& at, SelectionLog* log) {
  while (out.chosen.size() > 1) {
    int weakest = -1;
    double weakest_share = opt.min_val_improvement;
    EffectParams weakest_rest;
    std::optional<FitResult> all_early;  // all the chosen effects on the earlier fold, when needed
    for (std::size_t k = 0; k < out.chosen.size(); ++k) {
      std::vector<int> rest = out.chosen;
      rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(k));
      const EffectParams rest_start = only(ids_of(cands.specs, rest), at.base);
      const FitResult refit = fit_params(folds.fit, rest_start, joint_free_params(cands.specs, rest, rest_start));
      const double rest_val = mean_cost(folds.val, refit.effects);
      double share = rest_val > 0 ? 1.0 - at.val_cost / rest_val : 0.0;  // what the effect adds on validation
      if (share >= 0.0 && share < opt.inconclusive_share && !folds.early_val.segments.empty()) {
        // The later block cannot judge it: the earlier fold does, both sets refitted on its fit part.
        if (!all_early) all_early = fit_params(folds.early_fit, at.base, joint_free_params(cands.specs, out.chosen, at.base));
        const FitResult rest_early = fit_params(folds.early_fit, rest_start, joint_free_params(cands.specs, rest, rest_start));
        const double rest_cost = mean_cost(folds.early_val, rest_early.effects);
        if (rest_cost > 0) share = 1.0 - mean_cost(folds.early_val, all_early->effects) / rest_cost;
      }
      if (share < weakest_share) {
        weakest_share = share;
        weakest = static_cast<int>(k);
        weakest_rest = refit.effects;
      }
    }
    if (weakest < 0) break;
    if (log) {
      char line[512];
      std::snprintf(line, sizeof line, "backward: %s dropped (without it, the others refitted: validation cost %+.1f %%)",
                    cands[out.chosen[static_cast<std::size_t>(weakest)]].id.c_str(), 100 * (1.0 / (1.0 - weakest_share) - 1.0));
      log->push_back(line);
    }
    out.chosen.erase(out.chosen.begin() + weakest);
    at.base = weakest_rest;
    at.val_cost = mean_cost(folds.val, at.base);
  }
}

// After the forward rounds: an actuator's dynamics were chosen in the form that fitted best with
// only what came before it in the model (a lag chosen before the drag that slows the car, whose
// missing force also shows in the yaw rate). Each other form of the same actuator is fitted in its
// place with everything else that was chosen, all refitted together; it takes the place where
// it fits the fit part better (BIC, as many parameters or fewer) and does no worse on the later
// block, with its parameters inside their range.
void swap_dynamics_forms(const Folds& folds, const CandidateSet& cands, const std::vector<int>& pool,
                         const SelectionOptions& opt, double n_eff, GreedyResult& out, EffectParams& base,
                         SelectionLog* log) {
  for (std::size_t k = 0; k < out.chosen.size(); ++k) {
    const EffectSpec& current = cands[out.chosen[k]];
    if (current.dynamics_of.empty()) continue;
    double fit_cost = mean_cost(folds.fit, base), val_cost = mean_cost(folds.val, base);
    std::vector<int> rest = out.chosen;
    rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(k));
    const EffectParams rest_effects = only(ids_of(cands.specs, rest), base);
    for (int j : pool) {
      const EffectSpec& other = cands[j];
      const double extra_params =
          static_cast<double>(other.params.size()) - static_cast<double>(cands[out.chosen[k]].params.size());
      if (other.dynamics_of != current.dynamics_of || extra_params > 0.0 ||
          std::find(out.chosen.begin(), out.chosen.end(), j) != out.chosen.end())
        continue;
      std::vector<int> swapped = out.chosen;
      swapped[k] = j;
      FitResult trial = fit_effect(folds.fit, rest_effects, other);
      const FitResult joint = fit_params(folds.fit, trial.effects, joint_free_params(cands.specs, swapped, trial.effects));
      if (joint.cost < trial.cost) trial = joint;
      const double bic = n_eff * std::log(trial.cost / fit_cost) + extra_params * std::log(n_eff);
      const double trial_val = mean_cost(folds.val, trial.effects);
      if (!(bic < 0.0 && trial_val <= val_cost) || !range_limit_shortfall(other, trial.effects, opt.range_limit_margin).empty())
        continue;
      if (log) {
        char line[256];
        std::snprintf(line, sizeof line, "swap: %s in place of %s (with the rest refitted: dBIC %+.1f, validation cost %+.1f %%)",
                      other.id.c_str(), cands[out.chosen[k]].id.c_str(), bic, 100 * (trial_val / val_cost - 1.0));
        log->push_back(line);
      }
      out.chosen[k] = j;
      base = trial.effects;
      fit_cost = trial.cost;
      val_cost = trial_val;
    }
  }
}

}  // namespace

GreedyResult greedy(const Folds& folds, const CandidateSet& cands, const std::vector<int>& pool,
                    const SelectionOptions& opt, double n_eff, SelectionLog* log,
                    const std::vector<CandidateFit>* place_starts) {
  GreedyResult out;
  Chosen at;
  at.fit_cost = mean_cost(folds.fit, at.base);
  at.val_cost = mean_cost(folds.val, at.base);
  std::vector<bool> taken(cands.specs.size(), false);
  for (int round = 1; round <= opt.max_effects; ++round) {
    const std::optional<CandidateFit> pick =
        forward_round(folds, cands, pool, taken, at, round, opt, n_eff, out, log, place_starts);
    if (!pick) break;
    take(folds, cands, *pick, round, taken, out, at, log);
  }
  backward_eliminate(folds, cands, opt, out, at, log);
  swap_dynamics_forms(folds, cands, pool, opt, n_eff, out, at.base, log);
  out.effects = at.base;
  return out;
}

std::vector<Segment> resample_blocks(const std::vector<Segment>& segs, int block, std::mt19937_64& rng) {
  const int n = static_cast<int>(segs.size());
  const int blocks = std::max(1, (n + block - 1) / block);
  std::uniform_int_distribution<int> pick(0, blocks - 1);
  std::vector<Segment> out;
  for (int b = 0; b < blocks; ++b) {
    const int first = pick(rng) * block;
    for (int i = first; i < std::min(n, first + block); ++i) out.push_back(segs[static_cast<std::size_t>(i)]);
  }
  return out;
}

}  // namespace mppi::diagnose::selection
