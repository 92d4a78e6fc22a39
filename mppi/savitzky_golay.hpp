#pragma once
// Savitzky-Golay smoothing of a control sequence: each point is replaced by the value at that
// point of the least-squares polynomial (order p) through the window around it. Near the ends
// the window is shifted inwards (still w points), so polynomials of order <= p pass unchanged.
// Coefficients are computed once (T x w); apply() does no allocation.
#include <Eigen/Dense>
#include <vector>

#include "base/error.hpp"

namespace mppi {

class SavitzkyGolay {
 public:
  SavitzkyGolay() = default;
  SavitzkyGolay(int length, int window, int order) : length_(length), window_(window) {
    if (window < 1 || window % 2 == 0 || window > length || order < 0 || order >= window)
      throw Error("Savitzky-Golay: need odd window <= length and order < window");
    coeffs_.resize(static_cast<std::size_t>(length) * window);
    starts_.resize(static_cast<std::size_t>(length));
    const int half = window / 2;
    for (int i = 0; i < length; ++i) {
      const int start = std::clamp(i - half, 0, length - window);
      starts_[i] = start;
      // Vandermonde of offsets relative to i; the fitted value at i is row 0 of pinv(V).
      Eigen::MatrixXd vander(window, order + 1);
      for (int r = 0; r < window; ++r) {
        const double offset = start + r - i;
        double power = 1.0;
        for (int c = 0; c <= order; ++c, power *= offset) vander(r, c) = power;
      }
      const Eigen::MatrixXd pinv =
          (vander.transpose() * vander).ldlt().solve(vander.transpose());
      for (int r = 0; r < window; ++r)
        coeffs_[static_cast<std::size_t>(i) * window + r] = static_cast<float>(pinv(0, r));
    }
  }

  bool enabled() const { return length_ > 0; }
  int window() const { return window_; }
  // Weights applied to points start(i) .. start(i) + window - 1 to give point i.
  const float* weights(int i) const { return &coeffs_[static_cast<std::size_t>(i) * window_]; }
  int start(int i) const { return starts_[i]; }

  // out[i * stride] = smoothed in[...] for i < length; in and out must not alias.
  void apply(const float* in, float* out, int stride) const noexcept {
    for (int i = 0; i < length_; ++i) {
      const float* w = weights(i);
      float acc = 0.f;
      for (int r = 0; r < window_; ++r) acc += w[r] * in[(starts_[i] + r) * stride];
      out[i * stride] = acc;
    }
  }

 private:
  int length_ = 0;
  int window_ = 0;
  std::vector<float> coeffs_;  // length x window
  std::vector<int> starts_;    // length
};

}  // namespace mppi
