#include "diagnose/joint_refit.hpp"

#include <algorithm>
#include <cstdio>

#include "diagnose/identifiability.hpp"

namespace mppi::diagnose {

EffectParams joint_refit_start(const std::vector<SelectionRound>& rounds, const std::vector<std::string>& final_chosen,
                               const std::vector<std::string>& named, const EffectParams& fallback) {
  auto all_named = [&](const std::vector<std::string>& chosen) {
    return std::all_of(chosen.begin(), chosen.end(),
                       [&](const std::string& id) { return std::find(named.begin(), named.end(), id) != named.end(); });
  };
  if (all_named(final_chosen)) return fallback;
  EffectParams start = fallback;
  for (auto it = rounds.rbegin(); it != rounds.rend(); ++it) {
    if (!all_named(it->chosen)) continue;
    for (const std::string& id : it->chosen)
      for (const EffectParamSpec& p : effect_spec(id).params) start.*(p.member) = it->effects.*(p.member);
    break;
  }
  return start;
}

JointRefit refit_named_jointly(const FitProblem& all, const std::vector<std::string>& named_in, EffectParams start,
                               double range_limit_margin) {
  JointRefit out;
  std::vector<std::string> named = named_in;
  const EffectParams nominal_values;
  std::vector<double EffectParams::*> held;
  auto is_held = [&](double EffectParams::*m) { return std::find(held.begin(), held.end(), m) != held.end(); };
  char line[512];
  while (!named.empty()) {
    std::vector<ParamSpec> free;
    for (const auto& id : named) {
      const EffectSpec& s = effect_spec(id);
      for (std::size_t j = 0; j < s.params.size(); ++j) {
        if (s.data_grid == DataGrid::kTime && j == 0) continue;  // a change time: searched, not fitted
        if (effect_param_active(s.params[j], start) && !is_held(s.params[j].member)) free.push_back(s.params[j]);
      }
    }
    const FitResult joint = fit_params(all, start, free);
    std::vector<std::string> keep;
    bool changed = false;
    for (const auto& id : named) {
      const EffectSpec& spec = effect_spec(id);
      const int at = range_limit_param(spec, joint.effects, range_limit_margin);
      if (at < 0) {
        keep.push_back(id);
        continue;
      }
      changed = true;
      const std::string limit = range_limit_shortfall(spec, joint.effects, range_limit_margin);
      const EffectParamSpec& bound = spec.params[static_cast<std::size_t>(at)];
      bool others = false;
      for (std::size_t j = static_cast<std::size_t>(grid_param_count(spec.data_grid)); j < spec.params.size(); ++j)
        others = others || (static_cast<int>(j) != at && effect_param_active(spec.params[j], joint.effects) &&
                            !is_held(spec.params[j].member));
      if (others) {
        held.push_back(bound.member);
        keep.push_back(id);
        out.held.push_back(id + ": " + bound.name);
        std::snprintf(line, sizeof line, "joint refit: %s: %s; held at its nominal value %.4g, the rest refitted", id.c_str(),
                      limit.c_str(), nominal_values.*(bound.member));
        out.log.push_back(line);
        continue;
      }
      out.not_identified.emplace_back(id, limit);
      out.log.push_back("joint refit: " + id + " not identified: " + limit);
    }
    if (!changed) {
      out.kept = named;
      out.effects = joint.effects;
      out.params = joint.params;
      return out;
    }
    // The next pass starts from this one's values for what stays, the nominal for the rest.
    EffectParams next;
    for (const auto& id : keep)
      for (const EffectParamSpec& p : effect_spec(id).params) next.*(p.member) = joint.effects.*(p.member);
    for (auto m : held) next.*m = nominal_values.*m;
    start = next;
    named = keep;
  }
  return out;  // nothing identified
}

}  // namespace mppi::diagnose
