// Which effects to name: greedy forward selection judged on later data (forward validation),
// checked for identifiability (excitation, parameters at their search range's end), for
// stability (block-bootstrap refits) and, at the end, on the held-out part of the recording.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <random>

#include <tbb/parallel_for.h>

#include "base/error.hpp"
#include "diagnose/fit.hpp"
#include "diagnose/identifiability.hpp"
#include "diagnose/joint_refit.hpp"
#include "diagnose/ranking.hpp"

namespace mppi::diagnose {
namespace {

double heldout_1s_normalized_rmse(const ReplayModel& m, const DiagData& d, const std::vector<char>& mask,
                                  const ReplayOptions& o) {
  return horizon_metrics(m, d, mask, {1.0}, 5, o)[0].normalized_rmse;
}

// The parameters of these candidates that a joint least-squares refit moves at `at`: all but a
// change time, which was searched over the data, and an optional disc that is not there.
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

// Effect parameters of `ids` copied from `from`, everything else at its default.
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

struct CandidateFit {
  int index = -1;  // into the candidate list
  FitResult fit;
  double val_cost = 0, improvement = 0, bic = 0;
  bool passes = false;
  bool judged_early = false;  // passed on the earlier fold (the later block could not judge it)
  std::string earlier_fold;   // for the log: the earlier fold's verdict where it was asked
};

struct GreedyResult {
  std::vector<int> chosen;  // candidate indices in the order chosen
  EffectParams effects;
  std::vector<CandidateFit> first_round;  // every candidate of the pool, alone on the nominal
  std::vector<std::pair<int, std::string>> at_limit;  // passed, but a parameter is a bound
  std::vector<int> passed;  // every candidate that passed in some round
  // The fitted state after each round (its chosen effects refitted together), before backward
  // elimination: the ids chosen by then, and the effects.
  std::vector<SelectionRound> rounds;
};

// Greedy forward selection over `pool` (indices into cands): each round fits every remaining
// candidate on top of what is chosen and takes the one that lowers the validation cost most (the
// simplest among those nearly as good) among those that lower it enough and the BIC too, with
// identified parameters; a time-indexed change
// gives way to a state-dependent candidate that explains most of the same.
// The validation folds, forward in time: the main one (fit, then the later block), and an earlier
// one (the fit part's first half, then its second half) that judges a candidate the later block
// cannot judge: one that changes the later block's cost by less than opt.inconclusive_share (it
// acts on a place, a regime or a stretch of time that the later block does not reach).
struct Folds {
  const FitProblem& fit;
  const FitProblem& val;
  const FitProblem& early_fit;
  const FitProblem& early_val;
};

// The selection log: keeps each line (Selection::log) and echoes it as progress when asked.
class SelectionLog {
 public:
  SelectionLog(std::vector<std::string>* lines, const SelectionOptions& opt) : lines_(lines), progress_(&opt.progress) {}
  void push_back(const std::string& line) {
    if (lines_) lines_->push_back(line);
    if (*progress_) (*progress_)(line);
  }

 private:
  std::vector<std::string>* lines_;
  const std::function<void(const std::string&)>* progress_;
};

// The library effects a candidate stands for: itself, or for a joint candidate its two partners.
using Members = std::vector<std::vector<int>>;

// After the forward rounds: an actuator's dynamics were chosen in the form that fitted best with
// only what came before it in the model (a lag chosen before the drag that slows the car, whose
// missing force also shows in the yaw rate). Each other form of the same actuator is fitted in its
// place with everything else that was chosen, all refitted together; it takes the place where
// it fits the fit part better (BIC, as many parameters or fewer) and does no worse on the later
// block, with its parameters inside their range.
void swap_dynamics_forms(const Folds& folds, const std::vector<const EffectSpec*>& cands, const std::vector<int>& pool,
                         const SelectionOptions& opt, double n_eff, GreedyResult& out, EffectParams& base,
                         SelectionLog* log) {
  for (std::size_t k = 0; k < out.chosen.size(); ++k) {
    const EffectSpec& current = *cands[static_cast<std::size_t>(out.chosen[k])];
    if (current.dynamics_of.empty()) continue;
    double fit_cost = mean_cost(folds.fit, base), val_cost = mean_cost(folds.val, base);
    std::vector<int> rest = out.chosen;
    rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(k));
    const EffectParams rest_effects = only(ids_of(cands, rest), base);
    for (int j : pool) {
      const EffectSpec& other = *cands[static_cast<std::size_t>(j)];
      const double extra_params = static_cast<double>(other.params.size()) -
                                  static_cast<double>(cands[static_cast<std::size_t>(out.chosen[k])]->params.size());
      if (other.dynamics_of != current.dynamics_of || extra_params > 0.0 ||
          std::find(out.chosen.begin(), out.chosen.end(), j) != out.chosen.end())
        continue;
      std::vector<int> swapped = out.chosen;
      swapped[k] = j;
      FitResult trial = fit_effect(folds.fit, rest_effects, other);
      const FitResult joint = fit_params(folds.fit, trial.effects, joint_free_params(cands, swapped, trial.effects));
      if (joint.cost < trial.cost) trial = joint;
      const double bic = n_eff * std::log(trial.cost / fit_cost) + extra_params * std::log(n_eff);
      const double trial_val = mean_cost(folds.val, trial.effects);
      if (!(bic < 0.0 && trial_val <= val_cost) ||
          !range_limit_shortfall(other, trial.effects, opt.range_limit_margin).empty())
        continue;
      if (log) {
        char line[256];
        std::snprintf(line, sizeof line, "swap: %s in place of %s (with the rest refitted: dBIC %+.1f, validation cost %+.1f %%)",
                      other.id.c_str(), cands[static_cast<std::size_t>(out.chosen[k])]->id.c_str(), bic,
                      100 * (trial_val / val_cost - 1.0));
        log->push_back(line);
      }
      out.chosen[k] = j;
      base = trial.effects;
      fit_cost = trial.cost;
      val_cost = trial_val;
    }
  }
}

// `place_starts`: where given (a resample's selection), each place-dependent candidate is also
// refined from the place that the selection on all the data found for it, and keeps the better
// fit. A resample holds about two thirds of the data's blocks, fewer passes over the place, and
// the search over places alone then lands on another place as often as not (a grip patch that
// lowers the validation cost by 58 % on all the data found elsewhere, and worse, in 4 of 6
// resamples): stability should ask whether the resample's data support the effect, not whether
// a search from scratch finds it again.
GreedyResult greedy(const Folds& folds, const std::vector<const EffectSpec*>& cands, const Members& members,
                    const std::vector<int>& pool, const SelectionOptions& opt, double n_eff,
                    SelectionLog* log, const std::vector<CandidateFit>* place_starts = nullptr) {
  const FitProblem& fit = folds.fit;
  const FitProblem& val = folds.val;
  GreedyResult out;
  EffectParams base;
  double base_fit = mean_cost(fit, base), base_val = mean_cost(val, base);
  std::vector<bool> taken(cands.size(), false);
  char line[512];
  for (int round = 1; round <= opt.max_effects; ++round) {
    // The candidates of a round are fitted independently of each other (each on its own copy of
    // the model), so in parallel; the log and the ranking then go through them in pool order, so
    // the result does not depend on the number of threads.
    std::vector<int> todo;
    for (int i : pool)
      if (!taken[static_cast<std::size_t>(i)]) todo.push_back(i);
    std::vector<CandidateFit> tried(todo.size());
    tbb::parallel_for(std::size_t(0), todo.size(), [&](std::size_t n) {
      const int i = todo[n];
      const EffectSpec& spec = *cands[static_cast<std::size_t>(i)];
      CandidateFit& c = tried[n];
      c.index = i;
      c.fit = fit_effect(fit, base, spec);
      if (place_starts && spec.data_grid == DataGrid::kPlace)
        for (const CandidateFit& s : *place_starts)
          if (s.index == i) {
            FitResult from_main = fit_place_effect_from(fit, base, spec, s.fit.effects);
            // An identified fit is preferred to one with a parameter at its range's end (a third
            // patch of all the data grown to the largest radius on a resample's fewer passes).
            const bool main_identified = range_limit_shortfall(spec, from_main.effects, opt.range_limit_margin).empty();
            const bool search_identified = range_limit_shortfall(spec, c.fit.effects, opt.range_limit_margin).empty();
            if (main_identified != search_identified ? main_identified : from_main.cost < c.fit.cost)
              c.fit = std::move(from_main);
          }
      c.val_cost = mean_cost(val, c.fit.effects);
      const double k = static_cast<double>(spec.params.size());
      c.bic = n_eff * std::log(c.fit.cost / base_fit) + k * std::log(n_eff);
      c.improvement = 1.0 - c.val_cost / base_val;
      c.passes = c.improvement >= opt.min_val_improvement && c.bic <= -opt.min_bic_drop && c.val_cost < base_val;
      if (!c.passes && c.bic <= -opt.min_bic_drop && c.improvement >= 0.0 && c.improvement < opt.inconclusive_share &&
          !folds.early_val.segments.empty()) {
        const FitResult early = fit_effect(folds.early_fit, base, spec);
        const double early_base = mean_cost(folds.early_val, base);
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
    });
    for (const CandidateFit& c : tried) {
      if (log) {
        std::snprintf(line, sizeof line, "round %d: %-20s validation %+6.1f %%, dBIC %+9.1f%s%s", round,
                      cands[static_cast<std::size_t>(c.index)]->id.c_str(), 100 * (1.0 - c.val_cost / base_val), c.bic,
                      c.earlier_fold.c_str(), c.passes ? "  passes" : "");
        log->push_back(line);
      }
      if (c.passes && std::find(out.passed.begin(), out.passed.end(), c.index) == out.passed.end())
        out.passed.push_back(c.index);
    }
    if (round == 1) out.first_round = tried;
    // Improvements on different blocks do not compare: what passed on the later block (the main
    // fold) is ranked; what passed only on the earlier fold is considered when nothing else passes.
    std::vector<const CandidateFit*> order;
    for (const auto& c : tried)
      if (c.passes && !c.judged_early) order.push_back(&c);
    if (order.empty())
      for (const auto& c : tried)
        if (c.passes) order.push_back(&c);
    if (!order.empty()) {
      std::vector<RankedCandidate> ranked;
      for (const CandidateFit* c : order)
        ranked.push_back({c->improvement, c->bic, used_param_count(*cands[static_cast<std::size_t>(c->index)], c->fit)});
      const std::vector<const CandidateFit*> unranked = order;
      const std::vector<std::size_t> rank = rank_passing_candidates(ranked, opt.parsimony_share, opt.strong_bic_evidence);
      for (std::size_t k = 0; k < rank.size(); ++k) order[k] = unranked[rank[k]];
      // What the recording declares comes first: where the throttle column is a speed command,
      // the speed loop (when it passes) is the model's structure and the others compete on top
      // of it. A drive term that mimics the loop's feedforward (the motor's no-load speed scaled
      // to V / v_nl) would otherwise win on simplicity and take its place.
      const auto declared = std::find_if(order.begin(), order.end(), [&](const CandidateFit* c) {
        return cands[static_cast<std::size_t>(c->index)]->needs == Excitation::kSpeedCommand;
      });
      if (declared != order.end()) std::rotate(order.begin(), declared, declared + 1);
    }
    const CandidateFit* pick = nullptr;
    for (const CandidateFit* c : order) {
      const EffectSpec& spec = *cands[static_cast<std::size_t>(c->index)];
      const std::string limit = range_limit_shortfall(spec, c->fit.effects, opt.range_limit_margin);
      if (!limit.empty()) {
        out.at_limit.emplace_back(c->index, limit);
        if (log) log->push_back("round " + std::to_string(round) + ": " + spec.id + " not identified: " + limit);
        continue;
      }
      if (spec.data_grid == DataGrid::kTime) {
        // A change "from time t on" is also what a place or a state that the car reaches later
        // looks like; the state-dependent explanation wins when it does nearly as well.
        const CandidateFit* rival = nullptr;
        for (const auto& o : tried) {
          const EffectSpec& os = *cands[static_cast<std::size_t>(o.index)];
          if (os.data_grid == DataGrid::kTime || os.hook != EffectHook::kChassis) continue;
          if (o.improvement >= opt.time_change_dominance * c->improvement && (!rival || o.improvement > rival->improvement))
            rival = &o;
        }
        if (rival) {
          if (log)
            log->push_back("round " + std::to_string(round) + ": " + spec.id + " set aside: " +
                           cands[static_cast<std::size_t>(rival->index)]->id + " explains it as well without a clock");
          continue;
        }
      }
      pick = c;
      break;
    }
    if (!pick) {
      if (log) log->push_back("round " + std::to_string(round) + ": no candidate passes; stop");
      break;
    }
    // A joint candidate is chosen as its partners; a chosen effect takes the joint candidates it is in.
    const std::vector<int>& picked = members[static_cast<std::size_t>(pick->index)];
    for (std::size_t j = 0; j < cands.size(); ++j)
      for (int m : members[j])
        if (std::find(picked.begin(), picked.end(), m) != picked.end()) taken[j] = true;
    out.chosen.insert(out.chosen.end(), picked.begin(), picked.end());
    base = pick->fit.effects;
    base_fit = pick->fit.cost;
    base_val = pick->val_cost;
    if (log) {
      std::snprintf(line, sizeof line, "round %d: selected %s (validation %+.1f %%, dBIC %.1f)", round,
                    cands[static_cast<std::size_t>(pick->index)]->id.c_str(), 100 * pick->improvement, pick->bic);
      log->push_back(line);
    }
    // Each candidate was fitted with what came before held fixed; refit them together, so that the
    // next round does not pick an effect only because it makes up for an earlier one's bias.
    if (out.chosen.size() > 1) {
      const FitResult joint = fit_params(fit, base, joint_free_params(cands, out.chosen, base));
      if (joint.cost <= base_fit) {
        base = joint.effects;
        base_fit = joint.cost;
        base_val = mean_cost(val, base);
      }
    }
    out.rounds.push_back({ids_of(cands, out.chosen), base});
  }
  // Backward elimination: an effect whose removal (the others refitted together) costs less than
  // the improvement a new effect must bring on the validation data was made redundant by a later one.
  while (out.chosen.size() > 1) {
    int weakest = -1;
    double weakest_share = opt.min_val_improvement;
    EffectParams weakest_rest;
    std::optional<FitResult> all_early;  // all the chosen effects on the earlier fold, when needed
    for (std::size_t k = 0; k < out.chosen.size(); ++k) {
      std::vector<int> rest = out.chosen;
      rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(k));
      const EffectParams rest_start = only(ids_of(cands, rest), base);
      const FitResult refit = fit_params(fit, rest_start, joint_free_params(cands, rest, rest_start));
      const double rest_val = mean_cost(val, refit.effects);
      double share = rest_val > 0 ? 1.0 - base_val / rest_val : 0.0;  // what the effect adds on validation
      if (share >= 0.0 && share < opt.inconclusive_share && !folds.early_val.segments.empty()) {
        // The later block cannot judge it: the earlier fold does, both sets refitted on its fit part.
        if (!all_early) all_early = fit_params(folds.early_fit, base, joint_free_params(cands, out.chosen, base));
        const FitResult rest_early = fit_params(folds.early_fit, rest_start, joint_free_params(cands, rest, rest_start));
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
      std::snprintf(line, sizeof line, "backward: %s dropped (without it, the others refitted: validation cost %+.1f %%)",
                    cands[static_cast<std::size_t>(out.chosen[static_cast<std::size_t>(weakest)])]->id.c_str(),
                    100 * (1.0 / (1.0 - weakest_share) - 1.0));
      log->push_back(line);
    }
    out.chosen.erase(out.chosen.begin() + weakest);
    base = weakest_rest;
    base_val = mean_cost(val, base);
  }
  swap_dynamics_forms(folds, cands, pool, opt, n_eff, out, base, log);
  out.effects = base;
  return out;
}

// Block bootstrap of segments: blocks of consecutive segments drawn with replacement.
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


}  // namespace

Selection select_effects(const DiagData& d, const ModelFamily& nominal, const std::vector<char>& train_mask,
                         const std::vector<char>& heldout_mask, const SelectionOptions& opt,
                         const ReplayOptions& replay) {
  Selection sel;
  SelectionLog log(&sel.log, opt);
  const int len = std::max(2, static_cast<int>(std::lround(opt.fit_horizon_s / d.dt_s)));
  const auto segs = make_segments(d, train_mask, len, len);
  if (segs.size() < 6)
    throw Error(d.source + ": too little continuous training data: " + std::to_string(segs.size()) +
                " segments of " + std::to_string(opt.fit_horizon_s) + " s (need >= 6)");
  FitProblem all, fit, val;
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
  FitProblem early_fit = fit, early_val = fit;
  const std::size_t half = fit.segments.size() / 2;
  early_fit.segments.assign(fit.segments.begin(), fit.segments.begin() + static_cast<std::ptrdiff_t>(half));
  early_val.segments.assign(fit.segments.begin() + static_cast<std::ptrdiff_t>(half), fit.segments.end());
  if (early_fit.segments.size() < 3 || early_val.segments.size() < 3) early_val.segments.clear();
  const double n_fit = static_cast<double>(fit.segments.size() * static_cast<std::size_t>(len) * kChannels);
  const double n_eff = n_fit / opt.samples_per_independent;
  char line[512];
  std::snprintf(line, sizeof line, "fit on %zu segments of %.2f s up to t = %.1f s, validated on the %zu after",
                fit.segments.size(), len * d.dt_s, d.t[fit.segments.back().start], val.segments.size());
  log.push_back(line);

  // Candidates, and which of them this recording can identify at all.
  std::vector<const EffectSpec*> cands;
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
  Members members(cands.size());
  for (std::size_t i = 0; i < cands.size(); ++i) members[i] = {static_cast<int>(i)};
  std::deque<EffectSpec> joint_specs;
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
    joint_specs.push_back(std::move(joint));
    cands.push_back(&joint_specs.back());
    members.push_back({ia, ib});
  }
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
  const GreedyResult main = greedy(folds, cands, members, pool, opt, n_eff, &log);
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
    std::mt19937_64 rng(opt.seed * 0x9E3779B97F4A7C15ull + 17);
    const int block = std::max(2, static_cast<int>(std::lround(2.0 / (len * d.dt_s))));  // about 2 s
    // The resamples are drawn in order (one random stream), then selected on in parallel.
    std::vector<FitProblem> resampled(static_cast<std::size_t>(opt.stability_resamples), fit);
    for (FitProblem& fit_b : resampled) fit_b.segments = resample_blocks(fit.segments, block, rng);
    std::vector<std::vector<int>> chosen(resampled.size());
    std::mutex progress_mutex;
    int done = 0;
    tbb::parallel_for(std::size_t(0), resampled.size(), [&](std::size_t b) {
      chosen[b] = greedy({resampled[b], val, early_fit, early_val}, cands, members, stable_pool, opt, n_eff, nullptr,
                         &main.first_round).chosen;
      if (opt.progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        opt.progress("stability: resample " + std::to_string(++done) + " of " + std::to_string(opt.stability_resamples) + " done");
      }
    });
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
