#include "sysid/observability.hpp"

#include <cmath>
#include <cstdio>

#include "base/error.hpp"

namespace mppi::sysid {

bool ObservabilitySettings::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(relative_step > 0 && relative_step < 0.1)) return fail("relative_step must be in (0, 0.1)");
  if (!(rank_tolerance > 0 && rank_tolerance < 1)) return fail("rank_tolerance must be in (0, 1)");
  if (!(null_component > 0 && null_component < 1)) return fail("null_component must be in (0, 1)");
  if (horizon < 0) return fail("horizon must be >= 0");
  return true;
}

Mat numerical_jacobian(const TransitionFn& f, const Vec& x, const Vec& u, const Vec& scale,
                       double relative_step) {
  const int n = static_cast<int>(x.size());
  Mat J;
  for (int i = 0; i < n; ++i) {
    const double typical = scale.size() == n ? std::abs(scale(i)) : 1.0;
    const double step = relative_step * std::max({std::abs(x(i)), typical, 1e-12});
    Vec xp = x, xm = x;
    xp(i) += step;
    xm(i) -= step;
    const Vec d = (f(xp, u) - f(xm, u)) / (2 * step);
    if (i == 0) J.resize(d.size(), n);
    J.col(i) = d;
  }
  return J;
}

ObservabilityReport observability(const TransitionFn& f, const MeasurementFn& h,
                                  const std::vector<Vec>& xs, const std::vector<Vec>& us,
                                  const Vec& scale, const ObservabilitySettings& s) {
  std::string why;
  if (!s.is_valid(&why)) throw Error("observability: " + why);
  if (xs.empty() || xs.size() != us.size())
    throw Error("observability: need as many controls as states (and at least one point)");
  const int n = static_cast<int>(xs[0].size());
  if (scale.size() != 0 && scale.size() != n) throw Error("observability: scale must have n entries");
  const bool single = xs.size() == 1;
  const int steps = single ? (s.horizon > 0 ? s.horizon : n) : static_cast<int>(xs.size());
  std::vector<Mat> blocks;
  Mat Phi = Mat::Identity(n, n);
  int rows = 0;
  for (int k = 0; k < steps; ++k) {
    const Vec& x = xs[single ? 0 : k];
    const Vec& u = us[single ? 0 : k];
    if (x.size() != n) throw Error("observability: states of different sizes");
    const Mat C = numerical_jacobian(h, x, u, scale, s.relative_step);
    blocks.push_back(C * Phi);
    rows += static_cast<int>(C.rows());
    if (k + 1 < steps) {
      Phi = numerical_jacobian(f, x, u, scale, s.relative_step) * Phi;
      // Keep Phi's magnitude bounded over long horizons (row scaling comes later anyway).
      const double norm = Phi.norm();
      if (norm > 1e100 || (norm < 1e-100 && norm > 0)) Phi /= norm;
    }
  }
  Mat O(rows, n);
  int r0 = 0;
  for (const Mat& b : blocks) {
    O.middleRows(r0, b.rows()) = b;
    r0 += static_cast<int>(b.rows());
  }
  if (scale.size() == n) O = O * scale.cwiseAbs().asDiagonal();
  for (int r = 0; r < O.rows(); ++r) {
    const double norm = O.row(r).norm();
    if (norm > 0) O.row(r) /= norm;
  }
  Eigen::JacobiSVD<Mat> svd(O, Eigen::ComputeFullV);
  ObservabilityReport rep;
  rep.n = n;
  rep.singular_values = Vec::Zero(n);
  rep.singular_values.head(svd.singularValues().size()) = svd.singularValues();
  const double smax = rep.singular_values.size() ? rep.singular_values(0) : 0;
  rep.rank = 0;
  for (int i = 0; i < n; ++i)
    if (rep.singular_values(i) > s.rank_tolerance * smax) ++rep.rank;
  rep.null_space = svd.matrixV().rightCols(n - rep.rank);
  rep.weakest_direction = svd.matrixV().col(n - 1);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < rep.null_space.cols(); ++j)
      if (std::abs(rep.null_space(i, j)) > s.null_component) {
        rep.unobservable.push_back(i);
        break;
      }
  return rep;
}

std::string ObservabilityReport::describe(const std::vector<std::string>& names) const {
  auto name = [&](int i) { 
    if (i < static_cast<int>(names.size())) return names[i];
    std::string s = "x";
    s += std::to_string(i);
    return s;
  };
  std::string out = "rank " + std::to_string(rank) + " of " + std::to_string(n);
  if (full_rank()) {
    out += ": every state and parameter is locally identifiable";
    if (singular_values.size() && singular_values(0) > 0) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "\n  weakest direction (singular value ratio %.2g):",
                    singular_values(n - 1) / singular_values(0));
      out += buf;
      for (int i = 0; i < n; ++i) {
        if (std::abs(weakest_direction(i)) <= 0.1) continue;
        std::snprintf(buf, sizeof buf, " %+.2f %s", weakest_direction(i), name(i).c_str());
        out += buf;
      }
    }
    return out;
  }
  out += "; not identifiable:";
  for (std::size_t k = 0; k < unobservable.size(); ++k) {
    out += k ? ", " : " ";
    out += name(unobservable[k]);
  }
  for (int j = 0; j < null_space.cols(); ++j) {
    out += "\n  null direction ";
    out += std::to_string(j + 1);
    out += ":";
    for (int i = 0; i < n; ++i) {
      if (std::abs(null_space(i, j)) <= 0.05) continue;
      char buf[64];
      std::snprintf(buf, sizeof buf, " %+.2f %s", null_space(i, j), name(i).c_str());
      out += buf;
    }
  }
  return out;
}

}  // namespace mppi::sysid
