#pragma once
// Finite-horizon, time-varying discrete LQR for tracking a nominal trajectory: the deviation
// dynamics dx_{t+1} = A_t dx_t + B_t du_t, the cost
//   sum_{t<T} (dx_t' Q dx_t + du_t' R du_t) + dx_T' Qf dx_T,
// and the backward Riccati recursion from P_T = Qf:
//   S_t = R + B_t' P_{t+1} B_t,   K_t = -S_t^-1 B_t' P_{t+1} A_t,
//   P_t = Q + K_t' R K_t + (A_t + B_t K_t)' P_{t+1} (A_t + B_t K_t)
// (the Joseph form: equal to Q + A'PA - A'PB S^-1 B'PA at the optimal K, and a sum of
// positive semidefinite terms, so P stays symmetric PSD under rounding). The feedback is
//   u_t = u_nom_t + K_t (x_t - x_nom_t).
// Arithmetic in double whatever the input type. Runs once per control step, not per sample.
#include <Eigen/Dense>
#include <cstddef>
#include <span>
#include <string>

namespace mppi {

// One LQR problem. All matrices row-major. A weight may be given as its diagonal (n entries)
// or in full (n x n, symmetric).
template <class Real>
struct LqrProblem {
  int horizon = 0;  // T
  int nx = 0;       // states
  int nu = 0;       // controls
  std::span<const Real> a;   // T x nx x nx: A_t
  std::span<const Real> b;   // T x nx x nu: B_t
  std::span<const Real> q;   // Q: nx or nx x nx, positive semidefinite
  std::span<const Real> r;   // R: nu or nu x nu, positive definite
  std::span<const Real> qf;  // Qf: nx or nx x nx, positive semidefinite
};

// The recursion's matrices, sized for one (nx, nu). solve_lqr resizes it when the sizes
// change (allocating); later solves of the same sizes allocate nothing.
struct LqrWorkspace {
  LqrWorkspace() = default;
  LqrWorkspace(int nx, int nu) { resize(nx, nu); }
  void resize(int nx, int nu) {
    q.setZero(nx, nx);
    r.setZero(nu, nu);
    p.setZero(nx, nx);
    p_next.setZero(nx, nx);
    a.setZero(nx, nx);
    b.setZero(nx, nu);
    pb.setZero(nx, nu);
    s.setZero(nu, nu);
    k.setZero(nu, nx);
    rk.setZero(nu, nx);
    a_cl.setZero(nx, nx);
    p_a_cl.setZero(nx, nx);
    llt = Eigen::LLT<Eigen::MatrixXd>(nu);
  }
  int nx() const { return static_cast<int>(p.rows()); }
  int nu() const { return static_cast<int>(r.rows()); }

  Eigen::MatrixXd q, r;       // the weights (Qf is loaded into p)
  Eigen::MatrixXd p, p_next;  // P_{t+1}, then P_t
  Eigen::MatrixXd a, b;       // A_t, B_t
  Eigen::MatrixXd pb;         // P B
  Eigen::MatrixXd s;          // R + B'PB
  Eigen::MatrixXd k, rk;      // K_t, R K_t
  Eigen::MatrixXd a_cl;       // A + B K
  Eigen::MatrixXd p_a_cl;     // P (A + B K)
  Eigen::LLT<Eigen::MatrixXd> llt;
};

namespace detail {
template <class Real>
using ConstRowMajorMap = Eigen::Map<const Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
template <class Real>
using RowMajorMap = Eigen::Map<Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

// dst (n x n) from a weight given as its diagonal (n) or in full (n x n). False if neither.
template <class Real>
bool load_weight(std::span<const Real> w, int n, Eigen::MatrixXd& dst) {
  const auto size = static_cast<std::size_t>(n);
  if (w.size() == size) {
    dst.setZero();
    for (int i = 0; i < n; ++i) dst(i, i) = static_cast<double>(w[static_cast<std::size_t>(i)]);
    return true;
  }
  if (w.size() == size * size) {
    dst = ConstRowMajorMap<Real>(w.data(), n, n).template cast<double>();
    return true;
  }
  return false;
}
}  // namespace detail

// Gains K_t (T x nu x nx, row-major: gains[(t * nu + c) * nx + i]) of problem `pr`, and P_0
// (nx x nx, row-major) into p0 if p0 is not empty. False with the reason in *why (naming the
// argument) if a size is wrong, a weight is not finite or not (semi)definite, A_t or B_t is
// not finite, or R + B'PB is not positive definite at some t; gains are unspecified then.
template <class Real>
bool solve_lqr(const LqrProblem<Real>& pr, LqrWorkspace& ws, std::span<Real> gains, std::string* why,
               std::span<double> p0 = {}) {
  auto fail = [&](const std::string& reason) {
    if (why) *why = "lqr: " + reason;
    return false;
  };
  const int T = pr.horizon, nx = pr.nx, nu = pr.nu;
  if (T < 1 || nx < 1 || nu < 1) return fail("need horizon, nx, nu >= 1");
  const auto n_a = static_cast<std::size_t>(nx) * nx, n_b = static_cast<std::size_t>(nx) * nu,
             n_k = static_cast<std::size_t>(nu) * nx;
  if (pr.a.size() != n_a * T) return fail("a has " + std::to_string(pr.a.size()) + " entries, need T x nx x nx = " + std::to_string(n_a * T));
  if (pr.b.size() != n_b * T) return fail("b has " + std::to_string(pr.b.size()) + " entries, need T x nx x nu = " + std::to_string(n_b * T));
  if (gains.size() != n_k * T) return fail("gains has " + std::to_string(gains.size()) + " entries, need T x nu x nx = " + std::to_string(n_k * T));
  if (!p0.empty() && p0.size() != n_a) return fail("p0 has " + std::to_string(p0.size()) + " entries, need nx x nx = " + std::to_string(n_a));
  if (ws.nx() != nx || ws.nu() != nu) ws.resize(nx, nu);
  if (!detail::load_weight(pr.q, nx, ws.q)) return fail("q needs nx or nx x nx entries");
  if (!detail::load_weight(pr.r, nu, ws.r)) return fail("r needs nu or nu x nu entries");
  if (!detail::load_weight(pr.qf, nx, ws.p)) return fail("qf needs nx or nx x nx entries");
  if (!ws.q.allFinite() || !ws.r.allFinite() || !ws.p.allFinite()) return fail("a weight is not finite");
  // A negative diagonal entry rules out semidefiniteness; full weights are checked through S.
  for (int i = 0; i < nx; ++i)
    if (ws.q(i, i) < 0 || ws.p(i, i) < 0) return fail("q and qf need a diagonal >= 0");
  ws.llt.compute(ws.r);
  if (ws.llt.info() != Eigen::Success) return fail("r is not positive definite");

  for (int t = T - 1; t >= 0; --t) {
    const auto ut = static_cast<std::size_t>(t);
    ws.a = detail::ConstRowMajorMap<Real>(pr.a.data() + n_a * ut, nx, nx).template cast<double>();
    ws.b = detail::ConstRowMajorMap<Real>(pr.b.data() + n_b * ut, nx, nu).template cast<double>();
    if (!ws.a.allFinite() || !ws.b.allFinite())
      return fail("A_t or B_t is not finite at t = " + std::to_string(t));
    ws.pb.noalias() = ws.p * ws.b;
    ws.s = ws.r;
    ws.s.noalias() += ws.b.transpose() * ws.pb;
    ws.llt.compute(ws.s);
    if (ws.llt.info() != Eigen::Success)
      return fail("R + B'PB is not positive definite at t = " + std::to_string(t));
    ws.k.noalias() = ws.pb.transpose() * ws.a;  // B'PA (P symmetric)
    ws.llt.solveInPlace(ws.k);
    ws.k = -ws.k;
    ws.a_cl = ws.a;
    ws.a_cl.noalias() += ws.b * ws.k;
    ws.p_a_cl.noalias() = ws.p * ws.a_cl;
    ws.rk.noalias() = ws.r * ws.k;
    ws.p_next = ws.q;
    ws.p_next.noalias() += ws.a_cl.transpose() * ws.p_a_cl;
    ws.p_next.noalias() += ws.k.transpose() * ws.rk;
    ws.p = 0.5 * (ws.p_next + ws.p_next.transpose());  // symmetric to the last bit
    if (!ws.k.allFinite() || !ws.p.allFinite())
      return fail("the recursion overflowed at t = " + std::to_string(t));
    detail::RowMajorMap<Real>(gains.data() + n_k * ut, nu, nx) = ws.k.cast<Real>();
  }
  if (!p0.empty()) detail::RowMajorMap<double>(p0.data(), nx, nx) = ws.p;
  return true;
}

}  // namespace mppi
