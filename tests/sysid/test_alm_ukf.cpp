// The ALM-UKF's limited-memory unbiased noise estimators recover known noise statistics on a
// linear system (an independent oracle: the values the data was generated with).
#include <catch2/catch.hpp>

#include <random>

#include "sysid/alm_ukf.hpp"

using namespace mppi::sysid;

namespace {
struct Run {
  Vec q_hat, r_hat;
  Mat Q_hat, R_hat;
};

// x_{k+1} = A x + w, y = C x + v with w ~ N(q, Q), v ~ N(r, R). The statistics the filter
// estimates (process and/or measurement) start wrong; the others start at the truth.
Run run_alm(const Mat& A, const Mat& C, const Vec& q, const Mat& Q, const Vec& r, const Mat& R,
            int steps, int window, bool est_process, bool est_measurement, bool est_means) {
  const int nx = static_cast<int>(A.rows()), ny = static_cast<int>(C.rows());
  JointModel m{nx, 0, ny, [&](const Vec& x, const Vec&, const Vec&) -> Vec { return A * x; },
               [&](const Vec& x, const Vec&, const Vec&) -> Vec { return C * x; }};
  JointFilterSettings s;
  s.adaptive = true;
  s.alm.window = window;
  s.alm.min_samples = 50;
  s.alm.estimate_process = est_process;
  s.alm.estimate_measurement = est_measurement;
  s.alm.estimate_means = est_means;
  const Mat Q0 = est_process ? Mat(Mat::Identity(nx, nx) * 10.0 * Q.trace()) : Q;
  const Mat R0 = est_measurement ? Mat(Mat::Identity(ny, ny) * 0.2 * R.trace()) : R;
  JointStateFilter filt(m, s, Vec::Zero(nx), Mat::Identity(nx, nx), Vec(), Mat(0, 0), Q0, R0, Vec());
  if (!(est_process && est_means)) filt.ukf().set_process_noise(q, filt.ukf().Q());
  if (!(est_measurement && est_means)) filt.ukf().set_measurement_noise(r, filt.ukf().R());
  std::mt19937 rng(11);
  std::normal_distribution<double> n01;
  const Mat Lq = Eigen::LLT<Mat>(Q).matrixL(), Lr = Eigen::LLT<Mat>(R).matrixL();
  Vec x = Vec::Zero(nx);
  auto draw = [&](int n) {
    Vec v(n);
    for (int i = 0; i < n; ++i) v(i) = n01(rng);
    return v;
  };
  for (int k = 0; k < steps; ++k) {
    x = A * x + q + Lq * draw(nx);
    const Vec y = C * x + r + Lr * draw(ny);
    filt.step(Vec(), y, Vec());
  }
  return {filt.ukf().q(), filt.ukf().r(), filt.ukf().Q(), filt.ukf().R()};
}

struct LinearCase {
  Mat A = Mat(2, 2), C = Mat::Identity(2, 2), Q = Mat(2, 2), R = Mat(2, 2);
  Vec q = Vec(2), r = Vec(2);
  LinearCase() {
    A << 0.95, 0.1, -0.1, 0.9;
    Q << 0.04, 0.01, 0.01, 0.02;
    R << 0.09, 0.0, 0.0, 0.05;
    q << 0.1, -0.05;
    r << 0.3, -0.2;
  }
};
}  // namespace

// Statistical tolerances: 40000 samples; the relative sd of a variance estimate is about
// sqrt(2/N) = 0.7%, the filter's own settling adds more; 10% of the diagonal is far outside.
TEST_CASE("ALM-UKF estimates the measurement noise r, R of a linear system", "[sysid][alm]") {
  const LinearCase c;
  const Run run = run_alm(c.A, c.C, c.q, c.Q, c.r, c.R, 40000, 4000, false, true, true);
  INFO("R^ =\n" << run.R_hat << "\nr^ = " << run.r_hat.transpose());
  for (int i = 0; i < 2; ++i) {
    CHECK(run.R_hat(i, i) == Approx(c.R(i, i)).epsilon(0.10));
    CHECK(run.r_hat(i) == Approx(c.r(i)).margin(0.03));  // slow mode: see the docs
  }
  CHECK(run.R_hat(0, 1) == Approx(0.0).margin(0.005));
}

TEST_CASE("ALM-UKF estimates the process noise q, Q of a linear system", "[sysid][alm]") {
  const LinearCase c;
  const Run run = run_alm(c.A, c.C, c.q, c.Q, c.r, c.R, 40000, 4000, true, false, true);
  INFO("Q^ =\n" << run.Q_hat << "\nq^ = " << run.q_hat.transpose());
  for (int i = 0; i < 2; ++i) {
    CHECK(run.Q_hat(i, i) == Approx(c.Q(i, i)).epsilon(0.10));
    CHECK(run.q_hat(i) == Approx(c.q(i)).margin(0.01));
  }
  CHECK(run.Q_hat(0, 1) == Approx(c.Q(0, 1)).margin(0.004));
}

TEST_CASE("ALM estimators are unbiased for known residual samples", "[sysid][alm]") {
  // Feed the estimator synthetic samples whose covariance and correction are known:
  // r_k ~ N(m, S + Hs), correction Hs -> R^ must approach S.
  AlmSettings s;
  s.window = 20000;
  s.min_samples = 10;
  AlmNoiseEstimator est(1, 2, s);
  std::mt19937 rng(5);
  std::normal_distribution<double> n01;
  Mat S(2, 2), Hs(2, 2);
  S << 0.5, 0.1, 0.1, 0.3;
  Hs << 0.2, 0.05, 0.05, 0.1;
  const Mat L = Eigen::LLT<Mat>(S + Hs).matrixL();
  for (int k = 0; k < 20000; ++k) {
    UpdateInfo u;
    u.complete = true;
    Vec z(2);
    z << n01(rng), n01(rng);
    u.residual = Vec::Constant(2, 1.5) + L * z;
    u.h_spread = Hs;
    est.add_measurement_sample(u);
  }
  const Mat R = est.R_hat();
  CHECK(R(0, 0) == Approx(0.5).epsilon(0.04));
  CHECK(R(1, 1) == Approx(0.3).epsilon(0.04));
  CHECK(R(0, 1) == Approx(0.1).margin(0.015));
  CHECK(est.r_hat()(0) == Approx(1.5).margin(0.02));
  // Window: only the last N samples count.
  CHECK(est.measurement_samples() == 20000);
}

TEST_CASE("ALM projects an indefinite estimate to the nearest positive definite one", "[sysid][alm]") {
  AlmSettings s;
  s.window = 10;
  s.min_samples = 3;
  AlmNoiseEstimator est(1, 1, s);
  for (double v : {0.0, 0.1, -0.1, 0.05}) {
    UpdateInfo u;
    u.complete = true;
    u.residual = Vec::Constant(1, v);
    u.h_spread = Mat::Constant(1, 1, 1.0);  // correction larger than the sample spread
    est.add_measurement_sample(u);
  }
  bool projected = false;
  CHECK(est.R_hat_raw()(0, 0) < 0);
  CHECK(est.R_hat(&projected)(0, 0) == Approx(s.min_eigenvalue));
  CHECK(projected);
}

// Estimating Q and R together from these moment conditions is not identifiable: on this system
// the pair drifts to the degenerate fixed point R^ -> 0, Q^ inflated (the filter then follows the
// measurements). Both satisfy the residual moment equations; docs/ESTIMATION.md reports it.
// What must still hold: the filter's predicted residual covariance matches the residuals.
TEST_CASE("ALM-UKF with Q and R together stays consistent with its residuals", "[sysid][alm]") {
  const LinearCase c;
  const Run run = run_alm(c.A, c.C, c.q, c.Q, c.r, c.R, 40000, 4000, true, true, false);
  // Steady state of the filter with (Q^, R^): residual covariance predicted A P A^T + Q^ + R^,
  // where P solves the Riccati recursion; compare with the truth's residual covariance under
  // that filter, both from closed-form iterations (no sampling).
  Mat P = Mat::Identity(2, 2), Pt = Mat::Identity(2, 2);  // filter's P, true error covariance
  Mat K;
  for (int k = 0; k < 2000; ++k) {
    const Mat Pp = c.A * P * c.A.transpose() + run.Q_hat;
    const Mat S = Pp + run.R_hat;
    K = Pp * S.inverse();
    P = (Mat::Identity(2, 2) - K) * Pp;
    const Mat Ppt = c.A * Pt * c.A.transpose() + c.Q;
    const Mat IK = Mat::Identity(2, 2) - K;
    Pt = IK * Ppt * IK.transpose() + K * c.R * K.transpose();
  }
  const Mat S_filter = c.A * P * c.A.transpose() + run.Q_hat + run.R_hat;
  const Mat S_true = c.A * Pt * c.A.transpose() + c.Q + c.R;
  INFO("Q^ =\n" << run.Q_hat << "\nR^ =\n" << run.R_hat << "\nS filter\n" << S_filter << "\nS true\n" << S_true);
  for (int i = 0; i < 2; ++i) CHECK(S_filter(i, i) == Approx(S_true(i, i)).epsilon(0.10));
}
