#include "plot/ticks.hpp"

#include <cmath>
#include <cstdio>

#include "base/error.hpp"

namespace mppi::plot {

namespace {

// The nice steps m x 10^k (m in 1, 2, 5) from just below `raw` upwards.
double nice_step_at_least(double raw, int attempt) {
  static constexpr double kMantissa[3] = {1.0, 2.0, 5.0};
  const int k0 = static_cast<int>(std::floor(std::log10(raw))) - 1;
  const int k = k0 + attempt / 3;
  return kMantissa[attempt % 3] * std::pow(10.0, k);
}

std::vector<double> multiples(double lo, double hi, double step) {
  std::vector<double> t;
  const long first = std::lround(std::ceil(lo / step - 1e-9));
  const long last = std::lround(std::floor(hi / step + 1e-9));
  for (long i = first; i <= last; ++i) t.push_back(i == 0 ? 0.0 : static_cast<double>(i) * step);
  return t;
}

void check_finite(double a, double b, const char* what) {
  if (!std::isfinite(a) || !std::isfinite(b))
    throw Error(std::string(what) + ": axis range [" + std::to_string(a) + ", " + std::to_string(b) +
                "] is not finite");
}

}  // namespace

NiceAxis nice_axis(double data_min, double data_max, int max_intervals) {
  check_finite(data_min, data_max, "nice_axis");
  if (data_max < data_min) std::swap(data_min, data_max);
  if (max_intervals < 2) max_intervals = 2;
  if (data_max - data_min <= 1e-12 * std::max(1.0, std::abs(data_max))) {
    const double half = data_min == 0.0 ? 1.0 : 0.1 * std::abs(data_min);
    data_min -= half;
    data_max += half;
  }
  const double raw = (data_max - data_min) / max_intervals;
  for (int attempt = 0;; ++attempt) {
    const double step = nice_step_at_least(raw, attempt);
    const double lo = std::floor(data_min / step + 1e-9) * step;
    const double hi = std::ceil(data_max / step - 1e-9) * step;
    if (std::lround((hi - lo) / step) <= max_intervals) {
      NiceAxis a;
      a.lo = lo == 0.0 ? 0.0 : lo;
      a.hi = hi == 0.0 ? 0.0 : hi;
      a.step = step;
      a.ticks = multiples(a.lo, a.hi, step);
      return a;
    }
  }
}

NiceAxis ticks_inside(double lo, double hi, int max_intervals) {
  check_finite(lo, hi, "ticks_inside");
  if (!(hi > lo)) throw Error("ticks_inside: empty range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  if (max_intervals < 2) max_intervals = 2;
  const double raw = (hi - lo) / max_intervals;
  for (int attempt = 0;; ++attempt) {
    const double step = nice_step_at_least(raw, attempt);
    const std::vector<double> t = multiples(lo, hi, step);
    if (static_cast<int>(t.size()) <= max_intervals + 1) return {lo, hi, step, t};
  }
}

std::string tick_label(double value, double step) {
  char b[48];
  const double mag = std::max(std::abs(value), step);
  if (mag >= 1e6 || step < 1e-4) {
    // Exponent form with the digits that tell ticks apart.
    const int digits = std::max(0, static_cast<int>(std::ceil(std::log10(mag / step) - 1e-9)));
    std::snprintf(b, sizeof b, "%.*e", std::min(digits, 12), value);
    return b;
  }
  const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
  std::snprintf(b, sizeof b, "%.*f", decimals, std::abs(value) < 0.5 * step ? 0.0 : value);
  return b;
}

}  // namespace mppi::plot
