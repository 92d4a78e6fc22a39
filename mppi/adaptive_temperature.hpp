#pragma once
// The temperature that holds the effective sample size of the exponential weights at a target:
//   w_k(lambda) = exp(-(S_k - min S) / lambda),  ESS(lambda) = (sum w)^2 / sum w^2,
// which grows from the number of samples tied at the minimum (lambda -> 0) to the number of
// finite costs (lambda -> inf). solve_temperature() brackets the target from the previous
// temperature by doubling or halving, then bisects on log lambda until the ESS is within the
// tolerance: a handful of passes over the K costs when the costs change little from one step
// to the next, as they do in closed loop.
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

namespace mppi {

struct TemperatureTarget {
  float ess_share = 0.f;     // target ESS / K; 0 = fixed temperature
  float lambda_min = 1e-3f;  // bounds of the temperature [cost units]
  float lambda_max = 1e4f;
  float tolerance = 0.1f;    // accept an ESS within this share of the target
};

namespace detail {
// ESS at temperature lambda of the finite costs, whose minimum is min_cost.
inline double effective_sample_size(std::span<const float> costs, float min_cost, double lambda) {
  const double inv_lambda = 1.0 / lambda;
  double sum = 0.0, sum_sq = 0.0;
  for (float s : costs) {
    if (!std::isfinite(s)) continue;
    const double w = std::exp(-(static_cast<double>(s) - min_cost) * inv_lambda);
    sum += w;
    sum_sq += w * w;
  }
  return sum * sum / sum_sq;
}
inline float min_finite(std::span<const float> costs) {
  float m = std::numeric_limits<float>::infinity();
  for (float s : costs)
    if (std::isfinite(s)) m = std::min(m, s);
  return m;
}
}  // namespace detail

// ESS of the weights at temperature lambda; costs that are not finite weigh 0. 0 if none is.
inline double effective_sample_size(std::span<const float> costs, double lambda) {
  const float min_cost = detail::min_finite(costs);
  return std::isfinite(min_cost) ? detail::effective_sample_size(costs, min_cost, lambda) : 0.0;
}

// The temperature in [lambda_min, lambda_max] whose ESS is within tolerance of
// ess_share * costs.size(), starting from `previous`; the nearer bound when the target lies
// beyond it. *ess_out (if given) gets the ESS at the returned temperature.
inline float solve_temperature(std::span<const float> costs, const TemperatureTarget& target,
                               float previous, double* ess_out = nullptr) {
  const double want = std::max(1.0, static_cast<double>(target.ess_share) * static_cast<double>(costs.size()));
  const double tol = target.tolerance * want;
  const double lo_bound = target.lambda_min, hi_bound = target.lambda_max;
  const float min_cost = detail::min_finite(costs);
  auto effective_sample_size = [&](double l) {
    return std::isfinite(min_cost) ? detail::effective_sample_size(costs, min_cost, l) : 0.0;
  };
  double lambda = std::clamp(static_cast<double>(previous), lo_bound, hi_bound);
  double ess = effective_sample_size(lambda);
  auto done = [&](double l, double e) {
    if (ess_out) *ess_out = e;
    return static_cast<float>(l);
  };
  if (std::abs(ess - want) <= tol) return done(lambda, ess);
  // Bracket [lo, hi] with ESS(lo) < want < ESS(hi), moving by factors of 4 from lambda.
  double lo = lambda, hi = lambda;
  if (ess < want) {
    while (true) {
      lo = hi;
      hi = std::min(hi * 4.0, hi_bound);
      const double e = effective_sample_size(hi);
      if (std::abs(e - want) <= tol) return done(hi, e);
      if (e > want) break;
      if (hi >= hi_bound) return done(hi, e);
    }
  } else {
    while (true) {
      hi = lo;
      lo = std::max(lo / 4.0, lo_bound);
      const double e = effective_sample_size(lo);
      if (std::abs(e - want) <= tol) return done(lo, e);
      if (e < want) break;
      if (lo <= lo_bound) return done(lo, e);
    }
  }
  // Bisect on log lambda: ESS is monotone in lambda.
  double mid = std::sqrt(lo * hi), e = 0.0;
  for (int i = 0; i < 40; ++i) {
    mid = std::sqrt(lo * hi);
    e = effective_sample_size(mid);
    if (std::abs(e - want) <= tol) break;
    (e < want ? lo : hi) = mid;
  }
  return done(mid, e);
}

}  // namespace mppi
