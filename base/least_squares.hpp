#pragma once
// Box-constrained nonlinear least squares: Levenberg-Marquardt with a forward-difference
// Jacobian. The cost is whatever the residual function returns (e.g. the mean square of the
// residuals); the step is the damped Gauss-Newton step for the sum of squared residuals, with
// the damping scaled by the diagonal of J^T J, projected onto the box.
#include <functional>
#include <vector>

#include <Eigen/Core>

namespace mppi {

// Fills `residuals` for `params` and returns the cost to minimise. A non-finite cost marks a point
// that cannot be evaluated (a trial step there is rejected); residuals of a size other than the
// start's count as zero in a Jacobian.
using ResidualFunction = std::function<double(const Eigen::VectorXd& params, std::vector<double>* residuals)>;

struct LeastSquaresProblem {
  ResidualFunction residuals;
  Eigen::VectorXd lower, upper;  // the box (+-infinity where unbounded)
  // Forward-difference step of each parameter; stepped backwards where the forward step would
  // leave the box at the upper bound.
  Eigen::VectorXd difference_step;
  // Each step scaled by max(1, |parameter|) at the point of the difference (a relative step).
  bool step_scales_with_value = false;
};

struct LevenbergMarquardtOptions {
  int max_iterations = 40;           // Jacobians evaluated at most
  int tries_per_iteration = 12;      // damped steps tried per Jacobian before giving up
  double initial_damping = 1e-3;     // lambda at the start, relative to diag(J^T J)
  double damping_down = 3.0;         // lambda is divided by this after an accepted step ...
  double min_damping = 1e-9;         // ... but kept at least this
  double damping_up = 10.0;          // lambda is multiplied by this after a rejected step
  double relative_tolerance = 1e-5;  // stop once an accepted step lowers the cost by less than this share
};

struct LeastSquaresResult {
  Eigen::VectorXd params;
  std::vector<double> residuals;     // at params
  double cost = 0;                   // at params
  int iterations = 0;                // Jacobians evaluated in the loop
  int evaluations = 0;               // calls of the residual function
  std::vector<double> cost_history;  // at the start, then after each accepted step
};

// Minimises problem.residuals' cost from `start` (used as given: keep it inside the box). Stops
// after max_iterations, when no damped step of an iteration lowers the cost, when an accepted step
// lowers it by less than relative_tolerance (relative), or at once when there is no parameter, no
// residual or no finite cost at the start. Every accepted point has a finite cost below the last.
LeastSquaresResult levenberg_marquardt(const LeastSquaresProblem& problem, const Eigen::VectorXd& start,
                                       const LevenbergMarquardtOptions& options = {});

// J (residuals x parameters) at `params` by forward differences, `residuals_at_params` being the
// residuals there; `evaluations`, when given, counts the calls of the residual function.
Eigen::MatrixXd forward_difference_jacobian(const LeastSquaresProblem& problem, const Eigen::VectorXd& params,
                                            const std::vector<double>& residuals_at_params,
                                            int* evaluations = nullptr);

// J^T J, as a sum of dot products: a few parameters against many residuals needs no blocked
// matrix product, and Eigen's would open an OpenMP team inside each caller's parallel loop.
Eigen::MatrixXd normal_matrix(const Eigen::MatrixXd& jacobian);

// J^T J at a result's optimum (a fresh Jacobian there), for the parameters' covariance.
Eigen::MatrixXd normal_matrix_at(const LeastSquaresProblem& problem, const LeastSquaresResult& result);

}  // namespace mppi
