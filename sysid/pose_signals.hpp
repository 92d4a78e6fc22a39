#pragma once
// Signals derived from a recorded pose: an unwrapped angle and smoothed derivatives.
#include <vector>

namespace mppi::sysid::detail {

// The angle with its 2-pi jumps removed (NaN samples stay NaN and are skipped).
std::vector<double> unwrap(const std::vector<double>& a);
// d/dt of a local quadratic least-squares fit over +-hw samples (uneven times allowed); NaN where
// fewer than 3 samples are finite or the fit is singular.
std::vector<double> smooth_derivative(const std::vector<double>& t, const std::vector<double>& v, int hw);

}  // namespace mppi::sysid::detail
