#pragma once
// "Nice" axis ticks: steps of 1, 2 or 5 times a power of ten, limits on multiples of the step
// that cover the data, and labels printed with just the decimals the step needs.
#include <string>
#include <vector>

namespace mppi::plot {

struct NiceAxis {
  double lo = 0.0, hi = 1.0;  // limits: multiples of step with lo <= data min, hi >= data max
  double step = 1.0;          // 1, 2 or 5 x 10^k
  std::vector<double> ticks;  // lo, lo + step, ..., hi
};

// The smallest nice step that covers [data_min, data_max] with at most max_intervals steps
// (max_intervals >= 2). A zero-width range is widened first (by 10 % of |value|, or 1 at 0).
// Throws mppi::Error for non-finite input.
NiceAxis nice_axis(double data_min, double data_max, int max_intervals = 6);

// The smallest nice step such that [lo, hi] holds at most max_intervals steps (for limits that
// are fixed, e.g. by an equal scale); ticks are the step's multiples inside [lo, hi].
NiceAxis ticks_inside(double lo, double hi, int max_intervals = 6);

// A tick label: as many decimals as the step needs ("0.5", "12", "0.025"); exponent form
// for very large or very small values.
std::string tick_label(double value, double step);

}  // namespace mppi::plot
