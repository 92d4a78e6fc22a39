#include "sysid/pose_signals.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace mppi::sysid::detail {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;
}  // namespace

std::vector<double> unwrap(const std::vector<double>& a) {
  std::vector<double> out(a.size(), kNaN);
  double offset = 0, prev = kNaN;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i])) continue;
    if (!std::isnan(prev)) {
      const double d = a[i] - prev;
      if (d > kPi) offset -= 2 * kPi;
      if (d < -kPi) offset += 2 * kPi;
    }
    prev = a[i];
    out[i] = a[i] + offset;
  }
  return out;
}

std::vector<double> smooth_derivative(const std::vector<double>& t, const std::vector<double>& v, int hw) {
  const std::size_t n = t.size();
  std::vector<double> d(n, kNaN);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i >= static_cast<std::size_t>(hw) ? i - hw : 0;
    const std::size_t b = std::min(n - 1, i + hw);
    // Normal equations of v = c0 + c1 s + c2 s^2, s = t - t_i; derivative at s = 0 is c1.
    double S[5] = {0, 0, 0, 0, 0}, R[3] = {0, 0, 0};
    for (std::size_t j = a; j <= b; ++j) {
      if (std::isnan(v[j])) continue;
      const double s = t[j] - t[i];
      double p = 1;
      for (int k = 0; k < 5; ++k) {
        S[k] += p;
        if (k < 3) R[k] += p * v[j];
        p *= s;
      }
    }
    if (S[0] < 3) continue;
    const double M[3][3] = {{S[0], S[1], S[2]}, {S[1], S[2], S[3]}, {S[2], S[3], S[4]}};
    auto det3 = [](const double m[3][3]) {
      return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
             m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
             m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    };
    const double det = det3(M);
    if (!(std::abs(det) > 0)) continue;
    double M1[3][3];  // Cramer's rule for c1
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) M1[r][c] = c == 1 ? R[r] : M[r][c];
    d[i] = det3(M1) / det;
  }
  return d;
}

}  // namespace mppi::sysid::detail
