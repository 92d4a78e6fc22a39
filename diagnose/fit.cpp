#include "diagnose/fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Dense>

#include "base/error.hpp"
#include "base/least_squares.hpp"

namespace mppi::diagnose {

std::size_t used_param_count(const EffectSpec& spec, const FitResult& fit) {
  const EffectParams defaults;
  std::size_t used = 0;
  for (std::size_t j = 0; j < spec.params.size(); ++j) {
    if (!effect_param_active(spec.params[j], fit.effects)) continue;  // a disc the fit did not add
    // a place searched over the data, or a further disc the fit added (it lowered the cost clearly)
    if (static_cast<int>(j) < grid_param_count(spec.data_grid) || is_optional_disc_param(spec.params[j]) ||
        j >= fit.params.size()) {
      ++used;
      continue;
    }
    const double off = defaults.*(spec.params[j].member);
    const ParamEstimate& p = fit.params[j];
    if (!(p.stddev > 0) || std::abs(p.value - off) > 2.0 * p.stddev) ++used;
  }
  return std::max<std::size_t>(used, 1);
}
std::unique_ptr<ReplayModel> make_member_or_null(const ModelFamily& family, const EffectParams& e) {
  try {
    return family.make(e);
  } catch (const Error&) {
    return nullptr;
  }
}

namespace {

double residuals(const FitProblem& p, const EffectParams& e, std::vector<double>* r) {
  const auto m = make_member_or_null(*p.family, e);
  if (!m) {
    r->clear();
    return std::numeric_limits<double>::infinity();
  }
  segment_residuals(*m, *p.data, p.segments, p.scale, p.replay, r);
  double s = 0;
  for (double v : *r) s += v * v;
  return r->empty() ? 0.0 : s / static_cast<double>(r->size());
}

// Places the car visited in the problem's segments, spread out: farthest-point sampling.
std::vector<std::pair<double, double>> spread_places(const FitProblem& p, int count) {
  std::vector<std::pair<double, double>> visited;
  for (const auto& s : p.segments)
    for (int k = 0; k <= s.len; k += 5) visited.emplace_back(p.data->x[s.start + static_cast<std::size_t>(k)],
                                                             p.data->y[s.start + static_cast<std::size_t>(k)]);
  std::vector<std::pair<double, double>> chosen;
  if (visited.empty()) return chosen;
  std::vector<double> d2(visited.size(), std::numeric_limits<double>::infinity());
  std::size_t next = 0;
  for (int c = 0; c < count; ++c) {
    chosen.push_back(visited[next]);
    double far = -1;
    for (std::size_t i = 0; i < visited.size(); ++i) {
      const double dx = visited[i].first - chosen.back().first, dy = visited[i].second - chosen.back().second;
      d2[i] = std::min(d2[i], dx * dx + dy * dy);
      if (d2[i] > far) {
        far = d2[i];
        next = i;
      }
    }
    if (far <= 0) break;  // every visited place is chosen
  }
  return chosen;
}

// The estimates in the order of spec.params: the fitted ones from `fit`, every other parameter at
// its value in fit.effects with no spread (an optional disc that is not there).
std::vector<ParamEstimate> in_spec_order(const EffectSpec& spec, const FitResult& fit) {
  std::vector<ParamEstimate> out;
  for (const EffectParamSpec& q : spec.params) {
    const auto it = std::find_if(fit.params.begin(), fit.params.end(),
                                 [&](const ParamEstimate& e) { return e.name == q.name; });
    out.push_back(it != fit.params.end() ? *it : ParamEstimate{q.name, q.unit, fit.effects.*(q.member), 0.0});
  }
  return out;
}

}  // namespace

std::vector<ParamSpec> active_params(const EffectSpec& spec, const EffectParams& e) {
  std::vector<ParamSpec> out;
  for (const EffectParamSpec& q : spec.params)
    if (effect_param_active(q, e)) out.push_back(q);
  return out;
}

// A place-dependent effect (params: x, y, then the rest of its first disc, then optional further
// discs): the first disc's place is searched over places the car visited with a few sizes and
// strengths of the rest, then the best starts are refined by least squares in all its parameters
// (the edge is smooth). A further disc (grip_patch: up to three of one surface) is searched the
// same way with the discs found so far in place and kept when it lowers the cost clearly; each
// kept disc is refitted together with the others.
FitResult fit_place_effect(const FitProblem& p, const EffectParams& base, const EffectSpec& spec) {
  constexpr int kPlaces = 16, kStarts = 2;
  constexpr std::size_t kFirstDisc = 4;  // x, y, radius, strength
  const std::vector<ParamSpec> first(spec.params.begin(),
                                     spec.params.begin() + static_cast<std::ptrdiff_t>(std::min(kFirstDisc, spec.params.size())));
  const EffectParamSpec& px = first[0];
  const EffectParamSpec& py = first[1];
  const auto places = spread_places(p, kPlaces);
  struct Start {
    double cost;
    EffectParams e;
  };
  auto by_cost = [](const Start& a, const Start& b) { return a.cost < b.cost; };
  std::vector<Start> starts;
  for (const auto& [x, y] : places) {
    // The other parameters at a small and a large value on each side of their default.
    std::vector<EffectParams> variants(1, base);
    for (std::size_t i = 2; i < first.size(); ++i) {
      const EffectParamSpec& q = first[i];
      const double d = base.*(q.member);
      std::vector<EffectParams> next;
      for (const EffectParams& v : variants)
        for (double f : {0.25, 0.6}) {
          EffectParams e = v;
          // a size (from the default 0: a fraction of the range's top), a signed amount (off at 0:
          // as much each way) or a strength (below and above 1)
          const bool signed_amount = d == 0.0 && q.lo < 0.0 && q.hi > 0.0;
          e.*(q.member) = signed_amount ? 0.3 * (f < 0.5 ? q.lo : q.hi)
                          : d == 0.0    ? q.lo + f * 0.4 * (q.hi - q.lo)
                                        : (f < 0.5 ? d * 0.6 : d * 1.6);
          e.*(q.member) = std::clamp(e.*(q.member), q.lo, q.hi);
          next.push_back(e);
        }
      variants.swap(next);
    }
    for (EffectParams& e : variants) {
      e.*(px.member) = x;
      e.*(py.member) = y;
      starts.push_back({mean_cost(p, e), e});
    }
  }
  std::sort(starts.begin(), starts.end(), by_cost);
  FitResult best;
  best.cost = std::numeric_limits<double>::infinity();
  best.effects = base;
  for (std::size_t s = 0; s < starts.size() && s < kStarts; ++s) {
    if (!std::isfinite(starts[s].cost)) break;
    FitResult r = fit_params(p, starts[s].e, first, 10);
    if (r.cost < best.cost) best = r;
  }
  for (const OptionalDisc& disc : kOptionalPatchDiscs) {
    const auto radius_spec = std::find_if(spec.params.begin(), spec.params.end(),
                                          [&](const EffectParamSpec& q) { return q.member == disc.radius; });
    if (radius_spec == spec.params.end() || !std::isfinite(best.cost)) break;  // not this effect's disc
    const EffectParamSpec& radius = *radius_spec;
    starts.clear();
    for (const auto& [x, y] : places)
      for (double f : {0.25, 0.6}) {
        EffectParams e = best.effects;
        e.*(disc.x) = x;
        e.*(disc.y) = y;
        e.*(disc.radius) = radius.lo + f * 0.4 * (radius.hi - radius.lo);
        starts.push_back({mean_cost(p, e), e});
      }
    std::sort(starts.begin(), starts.end(), by_cost);
    FitResult more;
    more.cost = std::numeric_limits<double>::infinity();
    for (std::size_t s = 0; s < starts.size() && s < kStarts; ++s) {
      if (!std::isfinite(starts[s].cost) || starts[s].cost >= best.cost) break;
      FitResult r = fit_params(p, starts[s].e, active_params(spec, starts[s].e), 8);
      if (r.cost < more.cost) more = r;
    }
    // The level at which a whole effect counts as seen, so that a disc is not fitted to noise.
    if (!(more.cost < (1.0 - p.min_cost_gain) * best.cost) || !(more.effects.*(disc.radius) > 0.0)) break;
    best = more;
  }
  best.params = in_spec_order(spec, best);
  return best;
}

FitResult fit_place_effect_from(const FitProblem& p, const EffectParams& base, const EffectSpec& spec,
                                const EffectParams& start) {
  EffectParams e = base;
  for (const EffectParamSpec& q : spec.params) e.*(q.member) = start.*(q.member);
  FitResult r = fit_params(p, e, active_params(spec, e), 10);
  r.params = in_spec_order(spec, r);
  return r;
}

double mean_cost(const FitProblem& p, const EffectParams& e) {
  std::vector<double> r;
  return residuals(p, e, &r);
}

FitResult fit_params(const FitProblem& p, const EffectParams& base, const std::vector<ParamSpec>& free,
                     int max_iterations) {
  const int np = static_cast<int>(free.size());
  auto with = [&](const Eigen::VectorXd& v) {
    EffectParams e = base;
    for (int i = 0; i < np; ++i) e.*(free[static_cast<std::size_t>(i)].member) = v[i];
    return e;
  };
  LeastSquaresProblem problem;
  problem.residuals = [&](const Eigen::VectorXd& v, std::vector<double>* r) { return residuals(p, with(v), r); };
  problem.lower.resize(np);
  problem.upper.resize(np);
  problem.difference_step.resize(np);
  Eigen::VectorXd start(np);
  for (int i = 0; i < np; ++i) {
    const ParamSpec& s = free[static_cast<std::size_t>(i)];
    problem.lower[i] = s.lo;
    problem.upper[i] = s.hi;
    problem.difference_step[i] = 0.01 * s.scale;
    start[i] = base.*(s.member);
  }
  LevenbergMarquardtOptions options;
  options.max_iterations = max_iterations;
  options.tries_per_iteration = 8;
  options.initial_damping = 1e-3;
  options.damping_down = 3.0;
  options.min_damping = 1e-7;
  options.damping_up = 4.0;
  options.relative_tolerance = 1e-5;
  const LeastSquaresResult fit = levenberg_marquardt(problem, start, options);
  FitResult res;
  res.iterations = fit.iterations;
  res.cost = fit.cost;
  res.effects = with(fit.params);
  // Uncertainty: s^2 (J^T J)^-1 at the optimum, s^2 inflated by the residual correlation of
  // multi-step predictions (one independent sample in p.samples_per_independent).
  const std::size_t n = fit.residuals.size();
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(np, np);
  if (np > 0 && n > static_cast<std::size_t>(np) && std::isfinite(fit.cost)) {
    const double s2 = fit.cost * static_cast<double>(n) / static_cast<double>(n - static_cast<std::size_t>(np)) * p.samples_per_independent;
    cov = normal_matrix_at(problem, fit).completeOrthogonalDecomposition().pseudoInverse() * s2;
  }
  for (int i = 0; i < np; ++i) {
    const ParamSpec& s = free[static_cast<std::size_t>(i)];
    res.params.push_back({s.name, s.unit, fit.params[i], std::sqrt(std::max(0.0, cov(i, i)))});
  }
  return res;
}

FitResult fit_effect(const FitProblem& p, const EffectParams& base, const EffectSpec& spec) {
  if (spec.data_grid == DataGrid::kTime) {
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
  if (spec.data_grid == DataGrid::kPlace) return fit_place_effect(p, base, spec);
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

}  // namespace mppi::diagnose
