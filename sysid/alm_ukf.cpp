#include "sysid/alm_ukf.hpp"

#include <cmath>

#include "base/error.hpp"

namespace mppi::sysid {

bool AlmSettings::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (window < 3) return fail("alm window must be >= 3");
  if (min_samples < 3 || min_samples > window) return fail("alm min_samples must be in [3, window]");
  if (!(min_eigenvalue > 0 && std::isfinite(min_eigenvalue))) return fail("alm min_eigenvalue must be > 0");
  if (!(relative_floor > 0 && relative_floor < 1)) return fail("alm relative_floor must be in (0, 1)");
  return true;
}

Mat nearest_positive_definite_scaled(const Mat& A, const Vec& s, double floor) {
  const Vec inv = s.cwiseInverse();
  const Mat scaled = inv.asDiagonal() * A * inv.asDiagonal();
  return s.asDiagonal() * nearest_positive_definite(scaled, floor) * s.asDiagonal();
}

bool JointFilterSettings::is_valid(std::string* why) const {
  return ukf.is_valid(why) && alm.is_valid(why);
}

AlmNoiseEstimator::AlmNoiseEstimator(int nx, int ny, const AlmSettings& s) : settings_(s) {
  std::string why;
  if (!s.is_valid(&why)) throw Error("AlmNoiseEstimator: " + why);
  q_sum_ = Vec::Zero(nx);
  q_outer_ = q_corr_ = Mat::Zero(nx, nx);
  r_sum_ = Vec::Zero(ny);
  r_outer_ = r_corr_ = Mat::Zero(ny, ny);
}

void AlmNoiseEstimator::push(std::deque<Sample>& d, Sample s, Vec& sum, Mat& outer, Mat& corr) {
  sum += s.v;
  outer += s.v * s.v.transpose();
  corr += s.c;
  d.push_back(std::move(s));
  if (static_cast<int>(d.size()) > settings_.window) {
    const Sample& old = d.front();
    sum -= old.v;
    outer -= old.v * old.v.transpose();
    corr -= old.c;
    d.pop_front();
  }
}

void AlmNoiseEstimator::add_process_sample(const Vec& x_post, const Mat& P_post, const PredictInfo& pred) {
  push(qs_, {x_post - pred.f_mean, pred.f_spread - P_post}, q_sum_, q_outer_, q_corr_);
}

bool AlmNoiseEstimator::add_measurement_sample(const UpdateInfo& upd) {
  if (!upd.complete || upd.residual.size() != r_sum_.size()) return false;
  push(rs_, {upd.residual, upd.h_spread}, r_sum_, r_outer_, r_corr_);
  return true;
}

Vec AlmNoiseEstimator::q_hat() const { return qs_.empty() ? Vec(q_sum_ * 0) : Vec(q_sum_ / qs_.size()); }
Vec AlmNoiseEstimator::r_hat() const { return rs_.empty() ? Vec(r_sum_ * 0) : Vec(r_sum_ / rs_.size()); }

namespace {
// Unbiased sample covariance from running sums: (sum v v^T - n m m^T) / (n - 1).
Mat sample_cov(const Vec& sum, const Mat& outer, double n) {
  const Vec m = sum / n;
  return (outer - n * m * m.transpose()) / (n - 1);
}
}  // namespace

Mat AlmNoiseEstimator::Q_hat_raw() const {
  const double M = static_cast<double>(qs_.size());
  if (M < 2) return q_outer_ * 0;
  return sample_cov(q_sum_, q_outer_, M) - q_corr_ / M;
}

Mat AlmNoiseEstimator::R_hat_raw() const {
  const double N = static_cast<double>(rs_.size());
  if (N < 2) return r_outer_ * 0;
  return sample_cov(r_sum_, r_outer_, N) - r_corr_ / N;
}

Mat AlmNoiseEstimator::Q_hat(bool* projected) const {
  const Mat raw = Q_hat_raw();
  const Mat pd = nearest_positive_definite(raw, settings_.min_eigenvalue);
  if (projected) *projected = !(pd - 0.5 * (raw + raw.transpose())).isZero(0);
  return pd;
}

Mat AlmNoiseEstimator::R_hat(bool* projected) const {
  const Mat raw = R_hat_raw();
  const Mat pd = nearest_positive_definite(raw, settings_.min_eigenvalue);
  if (projected) *projected = !(pd - 0.5 * (raw + raw.transpose())).isZero(0);
  return pd;
}

namespace {
TransitionFn joint_f(const JointModel& m) {
  return [m](const Vec& xa, const Vec& u) {
    Vec out(m.nx + m.np);
    out.head(m.nx) = m.f(xa.head(m.nx), xa.tail(m.np), u);
    out.tail(m.np) = xa.tail(m.np);  // random walk; its noise is Q^p
    return out;
  };
}
MeasurementFn joint_h(const JointModel& m) {
  return [m](const Vec& xa, const Vec& u) { return m.h(xa.head(m.nx), xa.tail(m.np), u); };
}
const JointModel& checked(const JointModel& m) {
  if (m.nx < 1 || m.np < 0 || m.ny < 1 || !m.f || !m.h)
    throw Error("JointStateFilter: the model needs nx >= 1, np >= 0, ny >= 1 and both functions");
  return m;
}
}  // namespace

JointStateFilter::JointStateFilter(JointModel model, const JointFilterSettings& settings, const Vec& x0,
                                   const Mat& Px0, const Vec& p0, const Mat& Pp0, const Mat& Qx,
                                   const Mat& R, const Vec& param_noise_std)
    : model_(std::move(checked(model))),
      settings_(settings),
      param_noise_std_(param_noise_std),
      ukf_(model_.nx + model_.np, joint_f(model_), joint_h(model_), settings.ukf),
      alm_(model_.nx + model_.np, model_.ny, settings.alm) {
  const int nx = model_.nx, np = model_.np, n = nx + np;
  if (x0.size() != nx || Px0.rows() != nx || Px0.cols() != nx || Qx.rows() != nx || Qx.cols() != nx)
    throw Error("JointStateFilter: x0 / Px0 / Qx dimensions do not match nx = " + std::to_string(nx));
  if (p0.size() != np || Pp0.rows() != np || Pp0.cols() != np || param_noise_std.size() != np)
    throw Error("JointStateFilter: p0 / Pp0 / param_noise_std dimensions do not match np = " + std::to_string(np));
  if (R.rows() != model_.ny || R.cols() != model_.ny)
    throw Error("JointStateFilter: R must be ny x ny, ny = " + std::to_string(model_.ny));
  Vec xa(n);
  xa << x0, p0;
  Mat Pa = Mat::Zero(n, n);
  Pa.topLeftCorner(nx, nx) = Px0;
  Pa.bottomRightCorner(np, np) = Pp0;
  ukf_.reset(xa, Pa);
  Vec q = Vec::Zero(n);
  Mat Q = Mat::Zero(n, n);
  Q.topLeftCorner(nx, nx) = Qx;
  impose_param_noise(q, Q);
  ukf_.set_process_noise(q, Q);
  ukf_.set_measurement_noise(Vec::Zero(model_.ny), R);
  q_scale_ = Q.diagonal().cwiseMax(1e-30).cwiseSqrt();
  q_scale_.tail(np).setOnes();  // the parameter block is not estimated (re-imposed each step)
  r_scale_ = R.diagonal().cwiseMax(1e-30).cwiseSqrt();
}

void JointStateFilter::impose_param_noise(Vec& q, Mat& Q) const {
  const int nx = model_.nx, np = model_.np;
  q.tail(np).setZero();
  Q.block(0, nx, nx, np).setZero();
  Q.block(nx, 0, np, nx).setZero();
  Q.bottomRightCorner(np, np) = param_noise_std_.array().square().matrix().asDiagonal();
}

void JointStateFilter::step(const Vec& u_prev, const Vec& y, const Vec& u) {
  const Vec x_before = ukf_.x();
  const Mat P_before = ukf_.P();
  const PredictInfo pred = ukf_.predict(u_prev);  // copy: the next predict overwrites it
  last_update_ = ukf_.update(y, u);
  if (!ukf_.x().allFinite() || !ukf_.P().allFinite()) {
    // A diverged step (e.g. sigma points far outside the model's range): undo it, widen P a
    // little so that the next measurement can pull the state back.
    ukf_.x() = x_before;
    ukf_.P() = P_before + ukf_.Q();
    last_update_ = UpdateInfo{};
    ++rejected_;
    return;
  }
  if (!settings_.adaptive) return;
  const bool measured = !last_update_.rows.empty();
  if (measured && settings_.alm.estimate_process) alm_.add_process_sample(ukf_.x(), ukf_.P(), pred);
  if (settings_.alm.estimate_measurement) alm_.add_measurement_sample(last_update_);
  if (settings_.alm.estimate_process && alm_.process_ready()) {
    bool projected = false;
    Vec q = settings_.alm.estimate_means ? alm_.q_hat() : ukf_.q();
    Mat raw = alm_.Q_hat_raw();
    const int nx = model_.nx, np = model_.np;
    raw.block(0, nx, nx, np).setZero();
    raw.block(nx, 0, np, nx).setZero();
    raw.bottomRightCorner(np, np) = Mat::Identity(np, np);
    Mat Q = nearest_positive_definite_scaled(raw, q_scale_, settings_.alm.relative_floor);
    projected = !(Q - 0.5 * (raw + raw.transpose())).isZero(0);
    projections_ += projected;
    impose_param_noise(q, Q);
    ukf_.set_process_noise(q, Q);
  }
  if (settings_.alm.estimate_measurement && alm_.measurement_ready()) {
    bool projected = false;
    const Mat raw = alm_.R_hat_raw();
    const Mat R = nearest_positive_definite_scaled(raw, r_scale_, settings_.alm.relative_floor);
    projected = !(R - 0.5 * (raw + raw.transpose())).isZero(0);
    projections_ += projected;
    ukf_.set_measurement_noise(settings_.alm.estimate_means ? alm_.r_hat() : ukf_.r(), R);
  }
}

}  // namespace mppi::sysid
