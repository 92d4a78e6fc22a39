#include "sysid/diagnose/fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Dense>

#include "mppi/error.hpp"

namespace mppi::diagnose {
namespace {

// nullptr for parameters outside what the model accepts (treated as a bad point).
std::unique_ptr<ReplayModel> make_model(const ModelFamily& family, const EffectParams& e) {
  try {
    return family.make(e);
  } catch (const Error&) {
    return nullptr;
  }
}

double residuals(const FitProblem& p, const EffectParams& e, std::vector<double>* r) {
  const auto m = make_model(*p.family, e);
  if (!m) {
    r->clear();
    return std::numeric_limits<double>::infinity();
  }
  segment_residuals(*m, *p.data, p.segments, p.scale, p.replay, r);
  double s = 0;
  for (double v : *r) s += v * v;
  return r->empty() ? 0.0 : s / static_cast<double>(r->size());
}

double heldout_1s_normalized_rmse(const ReplayModel& m, const DiagData& d, const std::vector<char>& mask,
                                const ReplayOptions& o) {
  return horizon_metrics(m, d, mask, {1.0}, 5, o)[0].normalized_rmse;
}

}  // namespace

double mean_cost(const FitProblem& p, const EffectParams& e) {
  std::vector<double> r;
  return residuals(p, e, &r);
}

FitResult fit_params(const FitProblem& p, const EffectParams& base, const std::vector<ParamSpec>& free,
                     int max_iterations) {
  const int np = static_cast<int>(free.size());
  FitResult res;
  res.effects = base;
  auto with = [&](const Eigen::VectorXd& v) {
    EffectParams e = base;
    for (int i = 0; i < np; ++i) e.*(free[static_cast<std::size_t>(i)].member) = v[i];
    return e;
  };
  Eigen::VectorXd v(np);
  for (int i = 0; i < np; ++i) v[i] = base.*(free[static_cast<std::size_t>(i)].member);
  std::vector<double> r0, r1;
  double c0 = residuals(p, with(v), &r0);
  double mu = 1e-3;
  const std::size_t n = r0.size();
  Eigen::MatrixXd J(static_cast<Eigen::Index>(n), np);
  // J <- d residuals / d parameters at u (r0 = residuals at u): forward differences, stepping
  // inwards at the upper bounds.
  auto jacobian_at = [&](const Eigen::VectorXd& u) {
    for (int i = 0; i < np; ++i) {
      const ParamSpec& s = free[static_cast<std::size_t>(i)];
      double h = 0.01 * s.scale;
      if (u[i] + h > s.hi) h = -h;
      Eigen::VectorXd up = u;
      up[i] += h;
      residuals(p, with(up), &r1);
      if (r1.size() != n) r1.assign(n, 0.0);
      for (std::size_t k = 0; k < n; ++k) J(static_cast<Eigen::Index>(k), i) = (r1[k] - r0[k]) / h;
    }
  };
  for (int it = 0; it < max_iterations && np > 0 && std::isfinite(c0) && n > 0; ++it) {
    res.iterations = it + 1;
    jacobian_at(v);
    const Eigen::Map<const Eigen::VectorXd> rv(r0.data(), static_cast<Eigen::Index>(n));
    const Eigen::MatrixXd A = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * rv;
    bool improved = false;
    for (int tries = 0; tries < 8; ++tries) {
      Eigen::MatrixXd Am = A;
      for (int i = 0; i < np; ++i) Am(i, i) += mu * std::max(A(i, i), 1e-12);
      Eigen::VectorXd step = Am.ldlt().solve(-g);
      Eigen::VectorXd vn = v + step;
      for (int i = 0; i < np; ++i)
        vn[i] = std::clamp(vn[i], free[static_cast<std::size_t>(i)].lo, free[static_cast<std::size_t>(i)].hi);
      const double c1 = residuals(p, with(vn), &r1);
      if (std::isfinite(c1) && c1 < c0 && r1.size() == n) {
        const double rel = (c0 - c1) / c0;
        v = vn;
        r0.swap(r1);
        c0 = c1;
        mu = std::max(mu / 3, 1e-7);
        improved = true;
        if (rel < 1e-5) it = max_iterations;  // converged
        break;
      }
      mu *= 4;
    }
    if (!improved) break;
  }
  res.cost = c0;
  res.effects = with(v);
  // Uncertainty: s^2 (J^T J)^-1 at the optimum, s^2 inflated by the residual correlation of
  // multi-step predictions (about one independent sample in five).
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(np, np);
  if (np > 0 && n > static_cast<std::size_t>(np) && std::isfinite(c0)) {
    jacobian_at(v);
    const double s2 = c0 * static_cast<double>(n) / static_cast<double>(n - static_cast<std::size_t>(np)) * 5.0;
    const Eigen::MatrixXd A = J.transpose() * J;
    cov = A.completeOrthogonalDecomposition().pseudoInverse() * s2;
  }
  for (int i = 0; i < np; ++i) {
    const ParamSpec& s = free[static_cast<std::size_t>(i)];
    res.params.push_back({s.name, s.unit, v[i], std::sqrt(std::max(0.0, cov(i, i)))});
  }
  return res;
}

FitResult fit_effect(const FitProblem& p, const EffectParams& base, const EffectSpec& spec) {
  if (spec.time_grid) {
    // params[0] is a time: grid over the training span, LM on the rest at each; keep the best.
    double t0 = 1e18, t1 = -1e18;
    for (const auto& s : p.segments) {
      t0 = std::min(t0, p.data->t[s.start]);
      t1 = std::max(t1, p.data->t[s.start + static_cast<std::size_t>(s.len)]);
    }
    const std::vector<ParamSpec> rest(spec.params.begin() + 1, spec.params.end());
    FitResult best;
    best.cost = std::numeric_limits<double>::infinity();
    const int kGrid = 12;
    for (int g = 1; g < kGrid; ++g) {
      EffectParams e = base;
      const double tc = t0 + (t1 - t0) * g / kGrid;
      e.*(spec.params[0].member) = tc;
      FitResult r = fit_params(p, e, rest, 8);
      if (r.cost < best.cost) {
        best = r;
        best.params.insert(best.params.begin(),
                           {spec.params[0].name, spec.params[0].unit, tc, (t1 - t0) / kGrid / std::sqrt(12.0)});
      }
    }
    return best;
  }
  EffectParams start = base;
  if (!spec.grid.empty()) {
    double best = std::numeric_limits<double>::infinity();
    for (double g : spec.grid) {
      EffectParams e = base;
      e.*(spec.params[0].member) = g;
      const double c = mean_cost(p, e);
      if (c < best) {
        best = c;
        start = e;
      }
    }
  }
  return fit_params(p, start, spec.params);
}

Selection select_effects(const DiagData& d, const ModelFamily& nominal,
                         const std::vector<char>& train_mask, const std::vector<char>& heldout_mask,
                         const SelectionOptions& opt, const ReplayOptions& replay) {
  Selection sel;
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
  for (std::size_t i = 0; i < segs.size(); ++i) (i % 2 ? val : fit).segments.push_back(segs[i]);
  const double n_fit = static_cast<double>(fit.segments.size() * static_cast<std::size_t>(len) * kChannels);
  const double n_eff = n_fit / opt.samples_per_independent;

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

  const double held_nominal = heldout_1s_normalized_rmse(*nominal.make({}), d, heldout_mask, replay);
  EffectParams base;
  double base_fit = mean_cost(fit, base), base_val = mean_cost(val, base);
  char line[512];
  std::snprintf(line, sizeof line, "nominal: fit cost %.4f, validation cost %.4f (%zu + %zu segments of %.2f s)",
                base_fit, base_val, fit.segments.size(), val.segments.size(), len * d.dt_s);
  sel.log.push_back(line);
  std::vector<bool> taken(cands.size(), false);
  sel.candidates.resize(cands.size());
  for (int round = 1; round <= opt.max_effects; ++round) {
    int best = -1;
    double best_val = base_val, best_bic = 0;
    FitResult best_fit;
    for (std::size_t i = 0; i < cands.size(); ++i) {
      if (taken[i]) continue;
      const FitResult r = fit_effect(fit, base, *cands[i]);
      const double vc = mean_cost(val, r.effects);
      const double k = static_cast<double>(cands[i]->params.size());
      const double bic = n_eff * std::log(r.cost / base_fit) + k * std::log(n_eff);
      const double impr = 1.0 - vc / base_val;
      if (round == 1) {
        CandidateReport& c = sel.candidates[i];
        c.id = cands[i]->id;
        c.params = r.params;
        c.val_improvement = impr;
        c.bic_delta = bic;
        const auto m = make_model(nominal, r.effects);
        c.heldout_improvement =
            m ? 1.0 - heldout_1s_normalized_rmse(*m, d, heldout_mask, replay) / held_nominal : 0.0;
      }
      std::snprintf(line, sizeof line, "round %d: %-18s validation %+6.1f %%, dBIC %+9.1f", round,
                    cands[i]->id.c_str(), 100 * impr, bic);
      sel.log.push_back(line);
      if (impr >= opt.min_val_improvement && bic <= -opt.min_bic_drop && vc < best_val) {
        best = static_cast<int>(i);
        best_val = vc;
        best_bic = bic;
        best_fit = r;
      }
    }
    if (best < 0) {
      sel.log.push_back("round " + std::to_string(round) + ": no candidate passes; stop");
      break;
    }
    taken[static_cast<std::size_t>(best)] = true;
    sel.candidates[static_cast<std::size_t>(best)].selected = true;
    sel.candidates[static_cast<std::size_t>(best)].round_selected = round;
    sel.selected.push_back(cands[static_cast<std::size_t>(best)]->id);
    base = best_fit.effects;
    base_fit = best_fit.cost;
    base_val = best_val;
    std::snprintf(line, sizeof line, "round %d: selected %s (dBIC %.1f)", round,
                  cands[static_cast<std::size_t>(best)]->id.c_str(), best_bic);
    sel.log.push_back(line);
  }
  // Joint refit of every selected parameter on all training segments.
  std::vector<ParamSpec> free;
  std::vector<ParamEstimate> fixed_times;
  for (const auto& id : sel.selected) {
    const EffectSpec& s = effect_spec(id);
    for (std::size_t j = 0; j < s.params.size(); ++j) {
      if (s.time_grid && j == 0) {
        for (const auto& c : sel.candidates)
          if (c.id == id) fixed_times.push_back({s.params[0].name, s.params[0].unit, base.*(s.params[0].member), c.params[0].stddev});
        continue;
      }
      free.push_back(s.params[j]);
    }
  }
  const FitResult joint = fit_params(all, base, free);
  sel.final_effects = joint.effects;
  sel.final_params = fixed_times;
  sel.final_params.insert(sel.final_params.end(), joint.params.begin(), joint.params.end());
  return sel;
}

}  // namespace mppi::diagnose
