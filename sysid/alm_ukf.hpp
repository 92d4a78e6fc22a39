#pragma once
// The joint-state UKF and the adaptive limited-memory UKF (ALM-UKF) of the AutoRally paper
// ("Adaptive Limited Memory Unscented Kalman Filter", "Parameter Estimation"; You et al. 2017,
// after Myers & Tapley 1976).
//
// Joint state: parameters p appended to the state with random-walk dynamics p_{k+1} = p_k + w^p,
// x^a = [x; p]. The parameter noise Q^p is "rescaled to small positive values at each time step":
// its block of Q is reset to diag(param_noise_std^2), no cross terms, zero mean, every step.
//
// ALM: the noise statistics S = {q, Q, r, R} are re-estimated every step from the last N samples
//   r_k = y_k - h^_k,                     r^ = mean r_k,
//   R^ = 1/(N-1) sum (r_k - r^)(r_k - r^)^T - 1/N sum (E[h h^T]_k - h^_k h^_k^T)        (paper)
//   q_k = x^_k - f^_{k-1},                q^ = mean q_k,
//   Q^ = 1/(M-1) sum (q_k - q^)(q_k - q^)^T - 1/M sum (E[f f^T]_{k-1} - f^ f^T - P_k)
// and projected to the nearest positive definite matrix when an eigenvalue is below the floor.
// NOTE the sign of the last term of Q^: the paper prints "+"; Myers & Tapley (and the algebra:
// cov(q_k) = cov(K nu) = P_k|k-1 - P_k = (F P F^T + Q) - P_k) give "-". The "+" version is biased
// by twice that term; tests/sysid/test_alm_ukf.cpp checks the unbiased version recovers Q.
#include <deque>
#include <string>
#include <vector>

#include "sysid/ukf.hpp"

namespace mppi::sysid {

struct AlmSettings {
  int window = 500;             // N = M: residual samples kept (paper: the last 10 s of data)
  int min_samples = 50;         // no estimate until the window holds this many samples
  bool estimate_means = true;   // also estimate q and r (else they stay at their initial values)
  bool estimate_process = true;      // re-estimate q, Q
  bool estimate_measurement = true;  // re-estimate r, R
  double min_eigenvalue = 1e-10;     // floor of the projection to positive definite
  // JointStateFilter: the projection works in coordinates scaled by the initial noise standard
  // deviations, with eigenvalues >= relative_floor there (R^ >= 1% of the initial R per
  // channel by default), so that no channel is ever trusted as noise-free (units differ).
  double relative_floor = 0.01;

  bool is_valid(std::string* why) const;
};

// The limited-memory unbiased noise estimators alone (running sums over a sliding window).
class AlmNoiseEstimator {
 public:
  AlmNoiseEstimator(int nx, int ny, const AlmSettings& s);
  // One process-noise sample after an update: x_post = x^_k, P_post = P_k, from the prediction
  // that led to it (f^_{k-1}, E[f f^T] - f^ f^T).
  void add_process_sample(const Vec& x_post, const Mat& P_post, const PredictInfo& pred);
  // One measurement-noise sample (only complete measurements are used; returns whether used).
  bool add_measurement_sample(const UpdateInfo& upd);

  int process_samples() const { return static_cast<int>(qs_.size()); }
  int measurement_samples() const { return static_cast<int>(rs_.size()); }
  bool process_ready() const { return process_samples() >= settings_.min_samples; }
  bool measurement_ready() const { return measurement_samples() >= settings_.min_samples; }

  Vec q_hat() const;
  Vec r_hat() const;
  // Unbiased estimates, projected to eigenvalues >= min_eigenvalue; *projected (optional) says
  // whether the projection changed anything.
  Mat Q_hat(bool* projected = nullptr) const;
  Mat R_hat(bool* projected = nullptr) const;
  // The same before projection (may be indefinite), for tests.
  Mat Q_hat_raw() const;
  Mat R_hat_raw() const;

 private:
  struct Sample {
    Vec v;    // q_k or r_k
    Mat c;    // the correction term (E[ff^T]-f^f^T-P_k, or E[hh^T]-h^h^T)
  };
  void push(std::deque<Sample>& d, Sample s, Vec& sum, Mat& sum_outer, Mat& sum_corr);
  AlmSettings settings_;
  std::deque<Sample> qs_, rs_;
  Vec q_sum_, r_sum_;
  Mat q_outer_, r_outer_, q_corr_, r_corr_;
};

// A model with parameters for the joint-state filter.
struct JointModel {
  int nx = 0;  // states
  int np = 0;  // parameters
  int ny = 0;  // measurements
  std::function<Vec(const Vec& x, const Vec& p, const Vec& u)> f;  // x_{k+1} (no noise)
  std::function<Vec(const Vec& x, const Vec& p, const Vec& u)> h;  // y_k (no noise)
};

struct JointFilterSettings {
  UkfSettings ukf;
  bool adaptive = false;  // false: standard joint-state UKF; true: ALM-UKF
  AlmSettings alm;
  bool is_valid(std::string* why) const;
};

class JointStateFilter {
 public:
  // x0, Px0: initial state and covariance; p0, Pp0: initial parameters and covariance;
  // Qx, R: (initial) process noise of the states and measurement noise; param_noise_std: the
  // random-walk step of each parameter (Q^p = diag(std^2), re-imposed every step).
  JointStateFilter(JointModel model, const JointFilterSettings& settings, const Vec& x0,
                   const Mat& Px0, const Vec& p0, const Mat& Pp0, const Mat& Qx, const Mat& R,
                   const Vec& param_noise_std);

  // One step: predict with the control u_prev applied since the last sample, then update
  // with the measurement y (NaN = missing) taken with control u.
  void step(const Vec& u_prev, const Vec& y, const Vec& u);

  Vec state() const { return ukf_.x().head(model_.nx); }
  Vec params() const { return ukf_.x().tail(model_.np); }
  Vec param_std() const { return ukf_.P().diagonal().tail(model_.np).cwiseMax(0).cwiseSqrt(); }
  const Ukf& ukf() const { return ukf_; }
  Ukf& ukf() { return ukf_; }
  const JointModel& model() const { return model_; }
  const UpdateInfo& last_update() const { return last_update_; }
  int projections() const { return projections_; }  // times Q^ or R^ had to be projected
  int rejected_steps() const { return rejected_; }   // steps undone because the state went non-finite

 private:
  void impose_param_noise(Vec& q, Mat& Q) const;
  JointModel model_;
  JointFilterSettings settings_;
  Vec param_noise_std_;
  Ukf ukf_;
  AlmNoiseEstimator alm_;
  UpdateInfo last_update_;
  int projections_ = 0;
  int rejected_ = 0;
  Vec q_scale_, r_scale_;  // initial noise standard deviations (projection coordinates)
};

// The matrix nearest to A (Frobenius norm in the coordinates A_ij / (s_i s_j)) whose scaled
// eigenvalues are >= floor: returns S (S^-1 A S^-1 projected) S with S = diag(s).
Mat nearest_positive_definite_scaled(const Mat& A, const Vec& s, double floor);

}  // namespace mppi::sysid
