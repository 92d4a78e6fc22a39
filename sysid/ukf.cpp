#include "sysid/ukf.hpp"

#include <cmath>

#include "base/error.hpp"

namespace mppi::sysid {

bool UkfSettings::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(alpha > 0 && alpha <= 1)) return fail("alpha must be in (0, 1]");
  if (!(std::isfinite(beta) && beta >= 0)) return fail("beta must be >= 0");
  if (!(std::isfinite(kappa) && kappa >= 0)) return fail("kappa must be >= 0");
  if (!(min_eigenvalue > 0 && std::isfinite(min_eigenvalue))) return fail("min_eigenvalue must be > 0");
  return true;
}

SigmaWeights SigmaWeights::make(int n, const UkfSettings& s) {
  const double lambda = s.alpha * s.alpha * (n + s.kappa) - n;
  SigmaWeights w;
  w.spread = std::sqrt(n + lambda);
  w.wm = Vec::Constant(2 * n + 1, 1.0 / (2.0 * (n + lambda)));
  w.wc = w.wm;
  w.wm(0) = lambda / (n + lambda);
  w.wc(0) = w.wm(0) + 1 - s.alpha * s.alpha + s.beta;
  return w;
}

Mat nearest_positive_definite(const Mat& A, double min_eigenvalue) {
  const Mat S = 0.5 * (A + A.transpose());
  Eigen::SelfAdjointEigenSolver<Mat> es(S);
  if (es.info() != Eigen::Success) return Mat::Identity(A.rows(), A.cols()) * min_eigenvalue;
  if (es.eigenvalues().minCoeff() >= min_eigenvalue) return S;
  const Vec ev = es.eigenvalues().cwiseMax(min_eigenvalue);
  return es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
}

Mat sigma_points(const Vec& mean, const Mat& cov, double spread, double min_eigenvalue) {
  const int n = static_cast<int>(mean.size());
  Eigen::LLT<Mat> llt(0.5 * (cov + cov.transpose()));
  Mat L;
  if (llt.info() == Eigen::Success) {
    L = llt.matrixL();
  } else {
    Eigen::LLT<Mat> llt2(nearest_positive_definite(cov, min_eigenvalue));
    L = llt2.matrixL();
  }
  Mat X(n, 2 * n + 1);
  X.col(0) = mean;
  for (int j = 0; j < n; ++j) {
    X.col(1 + j) = mean + spread * L.col(j);
    X.col(1 + n + j) = mean - spread * L.col(j);
  }
  return X;
}

Ukf::Ukf(int nx, TransitionFn f, MeasurementFn h, const UkfSettings& settings)
    : nx_(nx), f_(std::move(f)), h_(std::move(h)), settings_(settings) {
  std::string why;
  if (!settings_.is_valid(&why)) throw Error("Ukf: invalid settings: " + why);
  if (nx_ < 1) throw Error("Ukf: need at least one state");
  if (!f_ || !h_) throw Error("Ukf: process and measurement functions must be set");
  w_ = SigmaWeights::make(nx_, settings_);
  x_ = Vec::Zero(nx_);
  P_ = Mat::Identity(nx_, nx_);
  q_ = Vec::Zero(nx_);
  Q_ = Mat::Zero(nx_, nx_);
}

void Ukf::reset(const Vec& x0, const Mat& P0) {
  if (x0.size() != nx_ || P0.rows() != nx_ || P0.cols() != nx_)
    throw Error("Ukf::reset: x0 / P0 dimensions do not match the state (" + std::to_string(nx_) + ")");
  x_ = x0;
  P_ = P0;
}

void Ukf::set_process_noise(const Vec& q, const Mat& Q) {
  if (q.size() != nx_ || Q.rows() != nx_ || Q.cols() != nx_)
    throw Error("Ukf::set_process_noise: q / Q dimensions do not match the state (" + std::to_string(nx_) + ")");
  q_ = q;
  Q_ = Q;
}

void Ukf::set_measurement_noise(const Vec& r, const Mat& R) {
  if (R.rows() != R.cols() || r.size() != R.rows() || R.rows() < 1)
    throw Error("Ukf::set_measurement_noise: r / R dimensions disagree");
  r_ = r;
  R_ = R;
}

const PredictInfo& Ukf::predict(const Vec& u) {
  const Mat X = sigma_points(x_, P_, w_.spread, settings_.min_eigenvalue);
  const int ns = static_cast<int>(X.cols());
  Mat F(nx_, ns);
  for (int i = 0; i < ns; ++i) {
    F.col(i) = f_(X.col(i), u);
    if (F.col(i).size() != nx_) throw Error("Ukf::predict: f returned a vector of the wrong size");
  }
  pinfo_.f_mean = F * w_.wm;
  const Mat D = F.colwise() - pinfo_.f_mean;
  pinfo_.f_spread = D * w_.wm.asDiagonal() * D.transpose();
  x_ = pinfo_.f_mean + q_;
  P_ = D * w_.wc.asDiagonal() * D.transpose() + Q_;
  P_ = 0.5 * (P_ + P_.transpose());
  return pinfo_;
}

const UpdateInfo& Ukf::update(const Vec& y, const Vec& u) {
  const int ny = this->ny();
  if (y.size() != ny)
    throw Error("Ukf::update: y has " + std::to_string(y.size()) + " entries, R is " + std::to_string(ny));
  uinfo_ = UpdateInfo{};
  for (int i = 0; i < ny; ++i)
    if (std::isfinite(y(i))) uinfo_.rows.push_back(i);
  uinfo_.complete = static_cast<int>(uinfo_.rows.size()) == ny;
  const int m = static_cast<int>(uinfo_.rows.size());
  if (m == 0) return uinfo_;
  const Mat X = sigma_points(x_, P_, w_.spread, settings_.min_eigenvalue);
  const int ns = static_cast<int>(X.cols());
  Mat Y(m, ns);
  for (int i = 0; i < ns; ++i) {
    const Vec hi = h_(X.col(i), u);
    if (hi.size() != ny) throw Error("Ukf::update: h returned a vector of the wrong size");
    for (int k = 0; k < m; ++k) Y(k, i) = hi(uinfo_.rows[k]);
  }
  Vec ym(m), rm(m);
  Mat Rm(m, m);
  for (int a = 0; a < m; ++a) {
    ym(a) = y(uinfo_.rows[a]);
    rm(a) = r_(uinfo_.rows[a]);
    for (int b = 0; b < m; ++b) Rm(a, b) = R_(uinfo_.rows[a], uinfo_.rows[b]);
  }
  const Vec h_mean = Y * w_.wm;
  const Mat DY = Y.colwise() - h_mean;
  const Mat DX = X.colwise() - x_;
  uinfo_.residual = ym - h_mean;
  uinfo_.h_spread = DY * w_.wm.asDiagonal() * DY.transpose();
  uinfo_.innovation = uinfo_.residual - rm;
  uinfo_.innovation_cov = DY * w_.wc.asDiagonal() * DY.transpose() + Rm;
  const Mat Pxy = DX * w_.wc.asDiagonal() * DY.transpose();
  const Eigen::LDLT<Mat> S(uinfo_.innovation_cov);
  const Mat K = S.solve(Pxy.transpose()).transpose();
  uinfo_.nis = uinfo_.innovation.dot(S.solve(uinfo_.innovation));
  x_ += K * uinfo_.innovation;
  P_ -= K * uinfo_.innovation_cov * K.transpose();
  P_ = 0.5 * (P_ + P_.transpose());
  return uinfo_;
}

}  // namespace mppi::sysid
