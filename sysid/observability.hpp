#pragma once
// Local observability of x_{k+1} = f(x_k, u_k), y_k = h(x_k, u_k) (use the joint-state model to
// ask which parameters can be identified): the rank of the linearised observability matrix
//   O = [C_0; C_1 A_0; C_2 A_1 A_0; ...],  A_k = df/dx, C_k = dh/dx at (x_k, u_k),
// Jacobians by central differences. One point repeated n times gives the classic
// [C; CA; ...; CA^{n-1}]; a trajectory gives the stacked (time-varying) form, which is what a
// filter running along that trajectory sees. Columns are scaled by typical magnitudes (so
// that "small" means the same for a mass and a tyre coefficient) and every row normalised
// (which changes neither rank nor null space). Null-space directions name the states /
// parameters that cannot be told apart from the chosen measurements.
#include <string>
#include <vector>

#include "sysid/ukf.hpp"

namespace mppi::sysid {

struct ObservabilitySettings {
  double relative_step = 1e-5;  // finite-difference step: relative_step * max(|x_i|, scale_i)
  double rank_tolerance = 1e-7; // singular values below tolerance * largest count as zero
  double null_component = 0.05; // a state is reported when |its entry| in a null vector exceeds this
  int horizon = 0;              // block rows for a single point (0 = n)

  bool is_valid(std::string* why) const;
};

struct ObservabilityReport {
  int n = 0;                      // state dimension
  int rank = 0;                   // numerical rank of O
  Vec singular_values;            // of the scaled, row-normalised O, descending
  Mat null_space;                 // n x (n - rank), scaled coordinates, unit columns
  std::vector<int> unobservable;  // indices with a significant entry in some null direction
  Vec weakest_direction;          // right singular vector of the smallest singular value

  bool full_rank() const { return rank == n; }
  // E.g. "rank 5 of 6; not identifiable: a, b (direction 0.71 a - 0.71 b)".
  std::string describe(const std::vector<std::string>& names) const;
};

// d f(x, u) / d x by central differences; `scale` (optional, size n) sets the step floor.
Mat numerical_jacobian(const TransitionFn& f, const Vec& x, const Vec& u, const Vec& scale,
                       double relative_step);

// xs, us: the linearisation points (one point or a trajectory); scale: typical magnitude of
// each state (empty = 1). Throws mppi::Error for inconsistent sizes.
ObservabilityReport observability(const TransitionFn& f, const MeasurementFn& h,
                                  const std::vector<Vec>& xs, const std::vector<Vec>& us,
                                  const Vec& scale = Vec(), const ObservabilitySettings& s = {});

}  // namespace mppi::sysid
