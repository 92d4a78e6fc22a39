#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "base/least_squares.hpp"

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double sum_of_squares(const std::vector<double>& r) {
  double s = 0;
  for (double v : r) s += v * v;
  return s;
}

mppi::LeastSquaresProblem unbounded(int np, double step) {
  mppi::LeastSquaresProblem p;
  p.lower = Eigen::VectorXd::Constant(np, -kInf);
  p.upper = Eigen::VectorXd::Constant(np, kInf);
  p.difference_step = Eigen::VectorXd::Constant(np, step);
  return p;
}

// Runs until no step lowers the cost (no relative stop).
mppi::LevenbergMarquardtOptions to_the_end() {
  mppi::LevenbergMarquardtOptions o;
  o.max_iterations = 200;
  o.relative_tolerance = 0;
  return o;
}

}  // namespace

TEST_CASE("levenberg_marquardt solves a linear least-squares problem as the normal equations do",
          "[core][least_squares]") {
  // A quadratic through 25 samples of a sine: x* = (A^T A)^-1 A^T b.
  const int m = 25;
  Eigen::MatrixXd a(m, 3);
  Eigen::VectorXd b(m);
  for (int i = 0; i < m; ++i) {
    const double t = 0.1 * i;
    a.row(i) << 1.0, t, t * t;
    b[i] = std::sin(t);
  }
  const Eigen::VectorXd expected = (a.transpose() * a).ldlt().solve(a.transpose() * b);
  mppi::LeastSquaresProblem p = unbounded(3, 1e-6);
  p.residuals = [&](const Eigen::VectorXd& x, std::vector<double>* r) {
    const Eigen::VectorXd e = a * x - b;
    r->assign(e.data(), e.data() + e.size());
    return sum_of_squares(*r);
  };
  const mppi::LeastSquaresResult res = mppi::levenberg_marquardt(p, Eigen::Vector3d(1, -1, 0.5), to_the_end());
  for (int j = 0; j < 3; ++j) CHECK(res.params[j] == Approx(expected[j]).margin(1e-7));
  CHECK(res.cost == Approx((a * expected - b).squaredNorm()).epsilon(1e-9));
  CHECK(res.cost_history.front() > res.cost);
  CHECK(res.cost_history.back() == res.cost);
  CHECK(res.residuals.size() == static_cast<std::size_t>(m));
  // J^T J at the optimum is A^T A (the residuals are linear).
  const Eigen::MatrixXd jtj = mppi::normal_matrix_at(p, res);
  const Eigen::MatrixXd ata = a.transpose() * a;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) CHECK(jtj(r, c) == Approx(ata(r, c)).epsilon(1e-6));
}

TEST_CASE("levenberg_marquardt stops on the box when the free minimum lies outside it", "[core][least_squares]") {
  // Minimum at (3, -2); the box is [0, 1] x [-1, 1]: the answer is the corner (1, -1).
  mppi::LeastSquaresProblem p;
  p.lower = Eigen::Vector2d(0, -1);
  p.upper = Eigen::Vector2d(1, 1);
  p.difference_step = Eigen::Vector2d(1e-4, 1e-4);
  p.residuals = [](const Eigen::VectorXd& x, std::vector<double>* r) {
    *r = {x[0] - 3.0, x[1] + 2.0};
    return sum_of_squares(*r);
  };
  const mppi::LeastSquaresResult res = mppi::levenberg_marquardt(p, Eigen::Vector2d(0.5, 0.0), to_the_end());
  CHECK(res.params[0] == 1.0);
  CHECK(res.params[1] == -1.0);
  CHECK(res.cost == Approx(5.0).epsilon(1e-12));
  for (int j = 0; j < 2; ++j) CHECK((res.params[j] >= p.lower[j] && res.params[j] <= p.upper[j]));
}

TEST_CASE("levenberg_marquardt fits y = a exp(b t) to noiseless data", "[core][least_squares]") {
  const double a_true = 2.5, b_true = -0.7;
  std::vector<double> t, y;
  for (int i = 0; i <= 30; ++i) {
    t.push_back(0.1 * i);
    y.push_back(a_true * std::exp(b_true * t.back()));
  }
  mppi::LeastSquaresProblem p = unbounded(2, 1e-7);
  p.step_scales_with_value = true;
  p.residuals = [&](const Eigen::VectorXd& x, std::vector<double>* r) {
    r->resize(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) (*r)[i] = x[0] * std::exp(x[1] * t[i]) - y[i];
    return sum_of_squares(*r) / static_cast<double>(t.size());
  };
  const mppi::LeastSquaresResult res = mppi::levenberg_marquardt(p, Eigen::Vector2d(1.0, 0.0), to_the_end());
  CHECK(res.params[0] == Approx(a_true).epsilon(1e-8));
  CHECK(res.params[1] == Approx(b_true).epsilon(1e-8));
  CHECK(res.cost < 1e-16);
  CHECK(res.iterations > 1);
  CHECK(res.evaluations > res.iterations * 2);
}

TEST_CASE("levenberg_marquardt rejects trial points whose cost is not finite", "[core][least_squares]") {
  // Minimum at x = 2, but the cost cannot be evaluated beyond x = 1 (NaN, or infinity with no
  // residuals): the answer approaches 1 from below and every cost it accepts is finite.
  const bool nan_cost = GENERATE(true, false);
  mppi::LeastSquaresProblem p = unbounded(1, 1e-6);
  p.residuals = [nan_cost](const Eigen::VectorXd& x, std::vector<double>* r) {
    if (x[0] > 1.0) {
      if (nan_cost) {
        *r = {x[0] - 2.0};
        return std::numeric_limits<double>::quiet_NaN();
      }
      r->clear();
      return kInf;
    }
    *r = {x[0] - 2.0};
    return sum_of_squares(*r);
  };
  mppi::LevenbergMarquardtOptions o = to_the_end();
  o.max_iterations = 30;
  const mppi::LeastSquaresResult res = mppi::levenberg_marquardt(p, Eigen::VectorXd::Zero(1), o);
  CHECK(std::isfinite(res.cost));
  CHECK(res.params[0] <= 1.0);
  CHECK(res.params[0] > 0.9);
  REQUIRE(res.cost_history.size() > 1);
  for (std::size_t k = 0; k < res.cost_history.size(); ++k) {
    CHECK(std::isfinite(res.cost_history[k]));
    if (k > 0) CHECK(res.cost_history[k] < res.cost_history[k - 1]);
  }
}

TEST_CASE("levenberg_marquardt returns the start when its cost is not finite", "[core][least_squares]") {
  mppi::LeastSquaresProblem p = unbounded(1, 1e-6);
  p.residuals = [](const Eigen::VectorXd&, std::vector<double>* r) {
    r->clear();
    return kInf;
  };
  const mppi::LeastSquaresResult res = mppi::levenberg_marquardt(p, Eigen::VectorXd::Constant(1, 0.25));
  CHECK(res.params[0] == 0.25);
  CHECK(res.iterations == 0);
  CHECK(res.evaluations == 1);
}
