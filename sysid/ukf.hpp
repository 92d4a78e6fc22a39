#pragma once
// The unscented Kalman filter of the AutoRally paper ("Unscented Kalman Filter", after Wan &
// van der Merwe 2000) for x_{k+1} = f(x_k, u_k) + w_k, y_k = h(x_k, u_k) + v_k with
// w ~ N(q, Q), v ~ N(r, R) (additive noise with means, as the paper writes it).
// Scaled sigma points: lambda = alpha^2 (n + kappa) - n, 2n + 1 points x +- sqrt(n + lambda) L_j
// (L L^T = P), W0m = lambda / (n + lambda), W0c = W0m + 1 - alpha^2 + beta, Wi = 1 / (2 (n + lambda)).
// Generic over the dimensions (Eigen dynamic sizes) and the user's process/measurement
// functions. Measurements may be partly missing (NaN entries are left out of the update).
// Not for per-sample hot loops: it allocates (std::function, dynamic Eigen).
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace mppi::sysid {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;

// x_{k+1} = f(x_k, u_k) without the noise; y_k = h(x_k, u_k) without the noise.
using TransitionFn = std::function<Vec(const Vec& x, const Vec& u)>;
using MeasurementFn = std::function<Vec(const Vec& x, const Vec& u)>;

struct UkfSettings {
  double alpha = 0.5;  // sigma-point spread (0, 1]: sqrt(n + lambda) = alpha sqrt(n + kappa)
  double beta = 2.0;   // prior knowledge of the distribution (2 = Gaussian)
  double kappa = 0.0;  // secondary scaling (>= 0 keeps n + kappa > 0)
  double min_eigenvalue = 1e-12;  // covariances are projected to eigenvalues >= this when not PD

  bool is_valid(std::string* why) const;
};

// The unscented transform's weights for dimension n.
struct SigmaWeights {
  Vec wm, wc;     // mean and covariance weights, 2n + 1 each
  double spread;  // sqrt(n + lambda)
  static SigmaWeights make(int n, const UkfSettings& s);
};

// 2n + 1 sigma points as columns: mean, mean + spread L_j, mean - spread L_j (L L^T = cov).
// A covariance that is not positive definite is projected first (nearest_positive_definite).
Mat sigma_points(const Vec& mean, const Mat& cov, double spread, double min_eigenvalue = 1e-12);

// The symmetric matrix nearest to A in the Frobenius norm with all eigenvalues >= min_eigenvalue
// (Higham 1988: symmetrise, clamp the eigenvalues). Returns A symmetrised when it already is.
Mat nearest_positive_definite(const Mat& A, double min_eigenvalue);

// What a prediction computed (the ALM-UKF's process-noise statistics use it).
struct PredictInfo {
  Vec f_mean;    // f^ = sum Wm f(X_i) (before adding q)
  Mat f_spread;  // E[f f^T] - f^ f^T = sum Wm f_i f_i^T - f^ f^T
};

// What an update computed (the ALM-UKF's measurement-noise statistics use it).
struct UpdateInfo {
  std::vector<int> rows;  // measured components used (finite entries of y)
  Vec residual;           // r_k = y - h^ (before subtracting r), on `rows`
  Mat h_spread;           // E[h h^T] - h^ h^T = sum Wm h_i h_i^T - h^ h^T, on `rows`
  Vec innovation;         // y - h^ - r
  Mat innovation_cov;     // S = sum Wc (h_i - h^)(h_i - h^)^T + R
  double nis = 0;         // normalised innovation squared nu^T S^-1 nu
  bool complete = false;  // every component of y was measured
};

class Ukf {
 public:
  // nx states; ny = size of the measurement (from R, set_measurement_noise). Throws
  // mppi::Error for invalid settings or dimensions.
  Ukf(int nx, TransitionFn f, MeasurementFn h, const UkfSettings& settings = {});

  void reset(const Vec& x0, const Mat& P0);
  void set_process_noise(const Vec& q, const Mat& Q);
  void set_measurement_noise(const Vec& r, const Mat& R);

  // x <- sum Wm f(X_i, u) + q, P <- sum Wc (f_i - x)(f_i - x)^T + Q.
  const PredictInfo& predict(const Vec& u);
  // Kalman update with y (NaN entries skipped; nothing happens if all are NaN).
  const UpdateInfo& update(const Vec& y, const Vec& u);

  int nx() const { return nx_; }
  int ny() const { return static_cast<int>(R_.rows()); }
  const Vec& x() const { return x_; }
  const Mat& P() const { return P_; }
  Vec& x() { return x_; }
  Mat& P() { return P_; }
  const Vec& q() const { return q_; }
  const Mat& Q() const { return Q_; }
  const Vec& r() const { return r_; }
  const Mat& R() const { return R_; }
  const UkfSettings& settings() const { return settings_; }
  const TransitionFn& transition() const { return f_; }
  const MeasurementFn& measurement() const { return h_; }

 private:
  int nx_;
  TransitionFn f_;
  MeasurementFn h_;
  UkfSettings settings_;
  SigmaWeights w_;
  Vec x_, q_, r_;
  Mat P_, Q_, R_;
  PredictInfo pinfo_;
  UpdateInfo uinfo_;
};

}  // namespace mppi::sysid
