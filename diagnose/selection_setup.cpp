// The selection's set-up (selection_stages.hpp): the training rows as fit problems (forward
// validation folds), and the candidate set with the joint candidates of partner terms.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "base/error.hpp"
#include "diagnose/selection_stages.hpp"

namespace mppi::diagnose::selection {


void make_problems(const PreparedRecording& d, const ModelFamily& nominal, const std::vector<char>& train_mask,
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
  all.samples_per_independent = fit.samples_per_independent = val.samples_per_independent = opt.samples_per_independent;
  all.min_cost_gain = fit.min_cost_gain = val.min_cost_gain = opt.min_val_improvement;
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

void make_candidates(const ModelFamily& nominal, const SelectionOptions& opt, std::vector<const EffectSpec*>* out,
                     Members* members_out, std::deque<EffectSpec>* joint_specs) {
  std::vector<const EffectSpec*>& cands = *out;
  Members& members = *members_out;
  if (opt.candidates.empty()) {
    for (const auto& e : effect_library())
      if (e.default_candidate && nominal.supports(e.id)) cands.push_back(&e);
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
  const std::size_t single_count = cands.size();
  for (std::size_t pa = 0; pa < single_count; ++pa) {
    const std::string& a = cands[pa]->id;
    const std::string& b = cands[pa]->partner;
    if (b.empty()) continue;
    const int ia = static_cast<int>(pa);
    int ib = -1;
    for (std::size_t i = 0; i < single_count; ++i)
      if (cands[i]->id == b) ib = static_cast<int>(i);
    if (ib < 0) continue;  // the partner is not a candidate here
    EffectSpec joint = *cands[static_cast<std::size_t>(ia)];
    joint.id = a + "+" + b;
    joint.description = "joint: " + joint.description + "; " + cands[static_cast<std::size_t>(ib)]->description;
    const auto& more = cands[static_cast<std::size_t>(ib)]->params;
    joint.params.insert(joint.params.end(), more.begin(), more.end());
    joint_specs->push_back(std::move(joint));
    cands.push_back(&joint_specs->back());
    members.push_back({ia, ib});
  }
}

}  // namespace mppi::diagnose::selection
