#include "base/least_squares.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <Eigen/Dense>

namespace mppi {

namespace {

// J <- d residuals / d params at `params` (`r0` the residuals there), one column per forward
// difference; `scratch` holds each stepped point's residuals.
void fill_jacobian(const LeastSquaresProblem& problem, const Eigen::VectorXd& params, const std::vector<double>& r0,
                   Eigen::MatrixXd& jacobian, std::vector<double>& scratch, int* evaluations) {
  const Eigen::Index np = params.size();
  const std::size_t n = r0.size();
  jacobian.resize(static_cast<Eigen::Index>(n), np);
  Eigen::VectorXd stepped = params;
  for (Eigen::Index j = 0; j < np; ++j) {
    double h = problem.difference_step[j];
    if (problem.step_scales_with_value) h *= std::max(1.0, std::abs(params[j]));
    if (params[j] + h > problem.upper[j]) h = -h;  // stay inside the box
    stepped[j] += h;
    problem.residuals(stepped, &scratch);
    if (evaluations) ++*evaluations;
    stepped[j] = params[j];
    if (scratch.size() != n) scratch.assign(n, 0.0);
    for (std::size_t k = 0; k < n; ++k) jacobian(static_cast<Eigen::Index>(k), j) = (scratch[k] - r0[k]) / h;
  }
}

Eigen::VectorXd clamped_to_box(const LeastSquaresProblem& problem, Eigen::VectorXd params) {
  for (Eigen::Index j = 0; j < params.size(); ++j)
    params[j] = std::clamp(params[j], problem.lower[j], problem.upper[j]);
  return params;
}

}  // namespace

Eigen::MatrixXd normal_matrix(const Eigen::MatrixXd& jacobian) { return jacobian.transpose().lazyProduct(jacobian); }

Eigen::MatrixXd forward_difference_jacobian(const LeastSquaresProblem& problem, const Eigen::VectorXd& params,
                                            const std::vector<double>& residuals_at_params, int* evaluations) {
  Eigen::MatrixXd jacobian;
  std::vector<double> scratch;
  fill_jacobian(problem, params, residuals_at_params, jacobian, scratch, evaluations);
  return jacobian;
}

Eigen::MatrixXd normal_matrix_at(const LeastSquaresProblem& problem, const LeastSquaresResult& result) {
  return normal_matrix(forward_difference_jacobian(problem, result.params, result.residuals));
}

LeastSquaresResult levenberg_marquardt(const LeastSquaresProblem& problem, const Eigen::VectorXd& start,
                                       const LevenbergMarquardtOptions& options) {
  LeastSquaresResult res;
  res.params = start;
  res.cost = problem.residuals(res.params, &res.residuals);
  ++res.evaluations;
  res.cost_history.push_back(res.cost);
  const Eigen::Index np = start.size();
  const std::size_t n = res.residuals.size();
  Eigen::MatrixXd jacobian;
  std::vector<double> trial;
  double damping = options.initial_damping;
  for (int it = 0; it < options.max_iterations && np > 0 && n > 0 && std::isfinite(res.cost); ++it) {
    res.iterations = it + 1;
    fill_jacobian(problem, res.params, res.residuals, jacobian, trial, &res.evaluations);
    const Eigen::Map<const Eigen::VectorXd> r(res.residuals.data(), static_cast<Eigen::Index>(n));
    const Eigen::MatrixXd jtj = normal_matrix(jacobian);
    const Eigen::VectorXd gradient = jacobian.transpose() * r;
    bool improved = false, converged = false;
    for (int tries = 0; tries < options.tries_per_iteration && !improved; ++tries) {
      Eigen::MatrixXd damped = jtj;
      for (Eigen::Index d = 0; d < np; ++d) damped(d, d) += damping * std::max(jtj(d, d), 1e-12);
      const Eigen::VectorXd next = clamped_to_box(problem, res.params + damped.ldlt().solve(-gradient));
      const double cost = problem.residuals(next, &trial);
      ++res.evaluations;
      if (std::isfinite(cost) && cost < res.cost && trial.size() == n) {
        converged = (res.cost - cost) / res.cost < options.relative_tolerance;
        res.params = next;
        res.residuals.swap(trial);
        res.cost = cost;
        res.cost_history.push_back(cost);
        damping = std::max(damping / options.damping_down, options.min_damping);
        improved = true;
      } else {
        damping *= options.damping_up;
      }
    }
    if (!improved || converged) break;
  }
  return res;
}

}  // namespace mppi
