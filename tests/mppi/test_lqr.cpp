// The ancillary feedback of Tube-MPPI: the time-varying LQR (mppi/lqr.hpp) against a Riccati
// recursion written here with plain loops and against the closed-form scalar DARE; the
// finite-difference Jacobians (mppi/linearize.hpp) against the kinematic bicycle's analytic
// derivatives; CpuBackend::ancillary_gains against a plain step loop, in closed loop, and on
// bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "dynamics/kinematic_bicycle.hpp"
#include "mppi/cpu_backend.hpp"
#include "mppi/linearize.hpp"
#include "mppi/lqr.hpp"
#include "tests/mppi/allocation_counter.hpp"
#include "tests/mppi/linear_system.hpp"

namespace {

using Matrix = std::vector<double>;  // row-major, sizes passed alongside

// x_{t+1} = A x_t + B u_t exactly (float), as an mppi::Dynamics model.
template <int Nx, int Nu>
struct LinearModel {
  static constexpr int kNx = Nx;
  static constexpr int kNu = Nu;
  std::array<float, Nx * Nx> a{};
  std::array<float, Nx * Nu> b{};
  std::size_t scratch_floats(int) const { return 0; }
  template <int W>
  void step(mppi::Batch<Nx, W> x, mppi::ConstBatch<Nu, W> u, float, float*) const noexcept {
    for (int j = 0; j < W; ++j) {
      float next[Nx];
      for (int i = 0; i < Nx; ++i) {
        float s = 0.f;
        for (int k = 0; k < Nx; ++k) s += a[i * Nx + k] * x[k][j];
        for (int c = 0; c < Nu; ++c) s += b[i * Nu + c] * u[c][j];
        next[i] = s;
      }
      for (int i = 0; i < Nx; ++i) x[i][j] = next[i];
    }
  }
};

struct ZeroCost {
  template <int Nx, int Nu, int W>
  void accumulate(mppi::ConstBatch<Nx, W>, mppi::ConstBatch<Nu, W>, int, float*) const noexcept {}
};

// ---- the oracle: K_t = -(R + B'PB)^-1 B'PA, P <- Q + A'PA - A'PB (R + B'PB)^-1 B'PA, with
// explicit loops and the closed-form inverse of a 1x1 or 2x2 S (not the library's Joseph form).
Matrix mul(const Matrix& x, const Matrix& y, int n, int m, int p) {  // (n x m) (m x p)
  Matrix z(static_cast<std::size_t>(n) * p, 0.0);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < m; ++k)
      for (int j = 0; j < p; ++j) z[i * p + j] += x[i * m + k] * y[k * p + j];
  return z;
}
Matrix transpose(const Matrix& x, int n, int m) {
  Matrix z(x.size());
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) z[j * n + i] = x[i * m + j];
  return z;
}
Matrix inverse_small(const Matrix& s, int nu) {
  if (nu == 1) return {1.0 / s[0]};
  REQUIRE(nu == 2);
  const double det = s[0] * s[3] - s[1] * s[2];
  return {s[3] / det, -s[1] / det, -s[2] / det, s[0] / det};
}
// Gains T x nu x nx for A_t = a[t], B_t = b[t] and full Q, R, Qf.
Matrix riccati_oracle(const std::vector<Matrix>& a, const std::vector<Matrix>& b, const Matrix& q,
                      const Matrix& r, const Matrix& qf, int nx, int nu) {
  const int T = static_cast<int>(a.size());
  Matrix gains(static_cast<std::size_t>(T) * nu * nx);
  Matrix p = qf;
  for (int t = T - 1; t >= 0; --t) {
    const Matrix bt = transpose(b[t], nx, nu), at = transpose(a[t], nx, nx);
    const Matrix btp = mul(bt, p, nu, nx, nx);
    Matrix s = mul(btp, b[t], nu, nx, nu);
    for (int i = 0; i < nu * nu; ++i) s[i] += r[i];
    const Matrix btpa = mul(btp, a[t], nu, nx, nx);
    const Matrix k = mul(inverse_small(s, nu), btpa, nu, nu, nx);  // without the minus sign
    for (int i = 0; i < nu * nx; ++i) gains[static_cast<std::size_t>(t) * nu * nx + i] = -k[i];
    const Matrix atpa = mul(mul(at, p, nx, nx, nx), a[t], nx, nx, nx);
    const Matrix correction = mul(transpose(btpa, nu, nx), k, nx, nu, nx);
    for (int i = 0; i < nx * nx; ++i) p[i] = q[i] + atpa[i] - correction[i];
  }
  return gains;
}
Matrix diagonal(std::initializer_list<double> d) {
  const int n = static_cast<int>(d.size());
  Matrix m(static_cast<std::size_t>(n) * n, 0.0);
  int i = 0;
  for (double v : d) m[i * n + i] = v, ++i;
  return m;
}
double max_abs(const Matrix& m) {
  double x = 0;
  for (double v : m) x = std::max(x, std::fabs(v));
  return x;
}

// A planar point mass with a slowly rotating velocity and cross-coupled inputs: 4 states, 2
// controls, every block of A and B populated; step t's A scaled to make it time-varying.
Matrix coupled_a(int t, double dt) {
  const double w = 0.3 * (1 + 0.5 * std::sin(0.7 * t));  // velocity rotation rate [rad/s]
  return {1, 0, dt, 0, 0, 1, 0, dt, 0, 0, 1, w * dt, 0, 0, -w * dt, 1};
}
Matrix coupled_b(double dt) {
  return {0.5 * dt * dt, 0, 0, 0.5 * dt * dt, dt, 0.2 * dt, -0.1 * dt, dt};
}

}  // namespace

TEST_CASE("solve_lqr gives the gains of a plain Riccati recursion on a time-varying system",
          "[lqr][mppi]") {
  constexpr int nx = 4, nu = 2, T = 30;
  const double dt = 0.1;
  std::vector<Matrix> a, b;
  std::vector<double> a_flat, b_flat;
  for (int t = 0; t < T; ++t) {
    a.push_back(coupled_a(t, dt));
    b.push_back(coupled_b(dt));
    a_flat.insert(a_flat.end(), a.back().begin(), a.back().end());
    b_flat.insert(b_flat.end(), b.back().begin(), b.back().end());
  }
  mppi::LqrWorkspace ws;
  std::vector<double> gains(static_cast<std::size_t>(T) * nu * nx);
  std::string why;
  // Both sides in double with O(T nx^3) operations in different orders (and the Joseph form
  // against the textbook one): agreement to ~1e-13 relative; 1e-9 leaves room, and a wrong
  // index or sign is off by O(1).
  SECTION("diagonal weights") {
    const std::vector<double> q{1.0, 2.0, 0.5, 0.1}, r{0.2, 0.4}, qf{10.0, 10.0, 1.0, 1.0};
    REQUIRE(mppi::solve_lqr<double>({T, nx, nu, a_flat, b_flat, q, r, qf}, ws, gains, &why));
    const Matrix expect = riccati_oracle(a, b, diagonal({1.0, 2.0, 0.5, 0.1}), diagonal({0.2, 0.4}),
                                         diagonal({10.0, 10.0, 1.0, 1.0}), nx, nu);
    const double scale = max_abs(expect);
    REQUIRE(scale > 0.1);
    for (std::size_t i = 0; i < gains.size(); ++i) CHECK(std::fabs(gains[i] - expect[i]) <= 1e-9 * scale);
  }
  SECTION("full weights") {
    const Matrix q{2.0, 0.5, 0.1, 0.0, 0.5, 1.0, 0.0, 0.2, 0.1, 0.0, 0.5, 0.0, 0.0, 0.2, 0.0, 0.3};
    const Matrix r{0.3, 0.1, 0.1, 0.2};
    Matrix qf = q;
    for (double& v : qf) v *= 5;
    REQUIRE(mppi::solve_lqr<double>({T, nx, nu, a_flat, b_flat, q, r, qf}, ws, gains, &why));
    const Matrix expect = riccati_oracle(a, b, q, r, qf, nx, nu);
    const double scale = max_abs(expect);
    for (std::size_t i = 0; i < gains.size(); ++i) CHECK(std::fabs(gains[i] - expect[i]) <= 1e-9 * scale);
  }
  SECTION("float input, P_0 out") {
    // float A, B, weights: the same problem rounded to float; the oracle gets the rounded values.
    std::vector<float> af(a_flat.begin(), a_flat.end()), bf(b_flat.begin(), b_flat.end());
    const std::vector<float> q{1.f, 2.f, 0.5f, 0.1f}, r{0.2f, 0.4f};
    std::vector<Matrix> ar, br;
    for (int t = 0; t < T; ++t) {
      ar.emplace_back(af.begin() + t * nx * nx, af.begin() + (t + 1) * nx * nx);
      br.emplace_back(bf.begin() + t * nx * nu, bf.begin() + (t + 1) * nx * nu);
    }
    std::vector<float> gf(gains.size());
    std::vector<double> p0(nx * nx);
    REQUIRE(mppi::solve_lqr<float>({T, nx, nu, af, bf, q, r, q}, ws, gf, &why, p0));
    const Matrix expect = riccati_oracle(ar, br, diagonal({1.0, 2.0, 0.5, 0.1}), diagonal({0.2, 0.4}),
                                         diagonal({1.0, 2.0, 0.5, 0.1}), nx, nu);
    const double scale = max_abs(expect);
    // the only float step is the rounding of each gain on output: 2^-24 relative
    for (std::size_t i = 0; i < gf.size(); ++i) CHECK(std::fabs(gf[i] - expect[i]) <= 1e-6 * scale);
    // P_0 is symmetric positive definite (Q > 0) and at least Q on the diagonal
    for (int i = 0; i < nx; ++i) {
      CHECK(p0[i * nx + i] >= q[i]);
      for (int j = 0; j < nx; ++j) CHECK(p0[i * nx + j] == p0[j * nx + i]);
    }
  }
}

TEST_CASE("solve_lqr converges to the closed-form scalar DARE gain over a long horizon", "[lqr][mppi]") {
  // x+ = a x + b u (open-loop unstable), cost q x^2 + r u^2. The DARE
  //   P = q + a^2 P - (a b P)^2 / (r + b^2 P)
  // times (r + b^2 P) is b^2 P^2 + (r - q b^2 - a^2 r) P - q r = 0; its positive root is P.
  const double a = 1.2, b = 0.5, q = 1.0, r = 0.1, qf = 3.0;
  const double lin = r - q * b * b - a * a * r;
  const double p_inf = (-lin + std::sqrt(lin * lin + 4 * b * b * q * r)) / (2 * b * b);
  const double k_inf = -a * b * p_inf / (r + b * b * p_inf);
  REQUIRE(std::fabs(a + b * k_inf) < 1);  // the closed loop is stable (sanity of the oracle)
  constexpr int T = 200;
  const std::vector<double> av(T, a), bv(T, b), qv{q}, rv{r}, qfv{qf};
  std::vector<double> gains(T), p0(1);
  mppi::LqrWorkspace ws(1, 1);
  std::string why;
  REQUIRE(mppi::solve_lqr<double>({T, 1, 1, av, bv, qv, rv, qfv}, ws, gains, &why, p0));
  // The recursion contracts by ~(a + b K)^2 = 0.04 per step: after 200 steps only rounding is
  // left (~1e-16 relative).
  CHECK(gains[0] == Approx(k_inf).epsilon(1e-10));
  CHECK(p0[0] == Approx(p_inf).epsilon(1e-10));
  // The last step sees only Qf: K = -a b qf / (r + b^2 qf).
  CHECK(gains[T - 1] == Approx(-a * b * qf / (r + b * b * qf)).epsilon(1e-12));

  SECTION("through the CPU backend (finite differences of a float model)") {
    LinearModel<1, 1> model;
    model.a = {static_cast<float>(a)};
    model.b = {static_cast<float>(b)};
    mppi::CpuBackend<LinearModel<1, 1>, ZeroCost> backend(model, {}, 1, T, 0.1f, 1);
    const std::vector<float> x0{0.f}, nominal(T, 0.f);
    std::vector<float> states(T + 1), gf(T);
    mppi::AncillaryWeights w{{static_cast<float>(q)}, {static_cast<float>(r)}, static_cast<float>(qf / q)};
    REQUIRE(backend.ancillary_gains(x0, nominal, w, states, gf, &why));
    // Along x = 0, u = 0 the perturbed lanes are a (+-h) and b (+-h), each rounded once: the
    // Jacobians are a and b to ~1e-7 relative (and a, b themselves rounded to float), which
    // moves the well-conditioned gain by a similar amount.
    CHECK(gf[0] == Approx(k_inf).epsilon(1e-5));
    CHECK(gf[T - 1] == Approx(-a * b * qf / (r + b * b * qf)).epsilon(1e-5));
  }
}

TEST_CASE("linearize_along matches the kinematic bicycle's analytic Jacobians", "[lqr][mppi]") {
  const mppi::KinematicBicycleParams params;
  const mppi::KinematicBicycle model(params);
  constexpr int nx = mppi::KinematicBicycle::kNx, nu = mppi::KinematicBicycle::kNu, T = 3;
  const float dt = 0.05f;
  using namespace mppi::state;
  using namespace mppi::control;
  struct Case {
    std::array<float, nx> x0;
    std::array<float, T * nu> u;  // steer, throttle per step
  };
  const Case cases[] = {
      {{3.f, -2.f, 0.7f, 5.f, 0.f, 0.3f, 0.f}, {0.3f, 0.5f, 0.35f, 0.4f, 0.2f, 0.6f}},
      {{-40.f, 25.f, -2.5f, 8.f, 0.f, -0.5f, 0.f}, {-0.6f, -0.2f, -0.5f, 0.f, -0.7f, 0.1f}},
      {{0.5f, 0.5f, 3.5f, 1.f, 0.f, 0.f, 0.f}, {0.05f, 1.f, 0.f, 0.9f, -0.1f, 0.8f}},
  };
  std::vector<float> scratch(mppi::linearize_scratch_floats(model));
  for (const Case& c : cases) {
    std::vector<float> states((T + 1) * nx), A(T * nx * nx), B(T * nx * nu);
    mppi::linearize_along(model, c.x0.data(), c.u.data(), T, dt, states.data(), A.data(), B.data(),
                          scratch.data());
    for (int t = 0; t < T; ++t) {
      // d(step)/d(x, u) at (x_t, u_t), from the step's equations (kinematic_bicycle.hpp):
      //   x+ = x + v cos(yaw) dt, y+ = y + v sin(yaw) dt, yaw+ = yaw + v kappa dt,
      //   v+ = v + (a_max thr - c v) dt, vy+ = 0, r+ = v+ kappa, roll+ = 0,
      //   kappa = tan(steer max_steer) / L.
      const float* x = states.data() + t * nx;
      const double yaw = x[kYaw], v = x[kVx];
      const double steer = c.u[t * nu + kSteer], thr = c.u[t * nu + kThrottle];
      const double delta = steer * params.max_steer_rad;
      const double kappa = std::tan(delta) / params.wheelbase_m;
      const double dkappa = params.max_steer_rad / (params.wheelbase_m * std::cos(delta) * std::cos(delta));
      const double damp = 1 - params.speed_damping_per_s * dt;
      const double v_next = v + (params.max_accel_mps2 * thr - params.speed_damping_per_s * v) * dt;
      double ea[nx][nx] = {}, eb[nx][nu] = {};
      ea[kX][kX] = 1, ea[kX][kYaw] = -v * std::sin(yaw) * dt, ea[kX][kVx] = std::cos(yaw) * dt;
      ea[kY][kY] = 1, ea[kY][kYaw] = v * std::cos(yaw) * dt, ea[kY][kVx] = std::sin(yaw) * dt;
      ea[kYaw][kYaw] = 1, ea[kYaw][kVx] = kappa * dt;
      ea[kVx][kVx] = damp;
      ea[kYawRate][kVx] = damp * kappa;
      eb[kYaw][kSteer] = v * dkappa * dt;
      eb[kVx][kThrottle] = params.max_accel_mps2 * dt;
      eb[kYawRate][kSteer] = v_next * dkappa;
      eb[kYawRate][kThrottle] = params.max_accel_mps2 * dt * kappa;
      // The largest error term is rounding: eps |x_{t+1}| / (2h). With |x| <= 41 m and the yaw
      // step h = 4.9e-3 max(1, |yaw|) >= 4.9e-3: 1.2e-7 * 41 / 9.8e-3 = 5e-4 at worst (x, y
      // columns are steps of 0.2 m there and err ~1e-5). Truncation h^2 |f'''| / 6 < 1e-5,
      // fast_sincos' 1e-7 over 2h < 1e-4. A wrong sign, factor or index is off by >= 1e-2.
      const double tol = 1e-3;
      for (int i = 0; i < nx; ++i) {
        for (int j = 0; j < nx; ++j) {
          INFO("t = " << t << " dx+[" << i << "]/dx[" << j << "]");
          CHECK(std::fabs(A[(t * nx + i) * nx + j] - ea[i][j]) <= tol);
        }
        for (int k = 0; k < nu; ++k) {
          INFO("t = " << t << " dx+[" << i << "]/du[" << k << "]");
          CHECK(std::fabs(B[(t * nx + i) * nu + k] - eb[i][k]) <= tol);
        }
      }
    }
  }
}

TEST_CASE("CpuBackend::ancillary_gains rolls the nominal out like a plain step loop", "[lqr][mppi]") {
  const mppi::KinematicBicycle model;
  constexpr int nx = mppi::KinematicBicycle::kNx, nu = mppi::KinematicBicycle::kNu, T = 25;
  const float dt = 0.02f;
  mppi::CpuBackend<mppi::KinematicBicycle, ZeroCost> backend(model, {}, 64, T, dt, 1);
  std::vector<float> x0{1.f, 2.f, 0.3f, 4.f, 0.f, 0.f, 0.f}, nominal(T * nu);
  for (int t = 0; t < T; ++t) {
    nominal[t * nu] = 0.5f * std::sin(0.3f * t);
    nominal[t * nu + 1] = 0.4f + 0.2f * std::cos(0.2f * t);
  }
  std::vector<float> states((T + 1) * nx), gains(T * nu * nx);
  std::string why;
  mppi::AncillaryWeights w{{1.f, 1.f, 2.f, 0.5f, 0.f, 0.f, 0.f}, {0.1f, 0.1f}, 5.f};
  REQUIRE(backend.ancillary_gains(x0, nominal, w, states, gains, &why));
  std::vector<float> x = x0;
  for (int t = 0; t <= T; ++t) {
    for (int i = 0; i < nx; ++i) {
      INFO("t = " << t << " state " << i);
      // the same float operations, one lane at a time; vectorised code may contract a
      // multiply-add differently (~1 ulp a step), hence a relative 1e-5
      CHECK(std::fabs(states[t * nx + i] - x[i]) <= 1e-5f * std::max(1.f, std::fabs(x[i])));
    }
    if (t < T) model.step<1>(mppi::Batch<nx, 1>{x.data()}, mppi::ConstBatch<nu, 1>{nominal.data() + t * nu}, dt, nullptr);
  }
  for (float g : gains) REQUIRE(std::isfinite(g));

  SECTION("later calls allocate nothing") {
    // counts operator new (std::vector, std::string); Eigen's matrices are sized in the
    // workspace on the first call and reused, but Eigen allocates through malloc, not counted
    const long n = mppi::test::allocations_in([&] { backend.ancillary_gains(x0, nominal, w, states, gains, &why); });
    CHECK(n == 0);
  }
}

TEST_CASE("CpuBackend::ancillary_gains: the gains of a linear model match the oracle and stabilise",
          "[lqr][mppi]") {
  constexpr int nx = 4, nu = 2, T = 60;
  const double dt = 0.1;
  LinearModel<nx, nu> model;
  const Matrix a = coupled_a(0, dt), b = coupled_b(dt);
  std::copy(a.begin(), a.end(), model.a.begin());
  std::copy(b.begin(), b.end(), model.b.begin());
  std::vector<Matrix> a_rounded(T), b_rounded(T);  // the model's A, B as the floats it uses
  for (int t = 0; t < T; ++t) {
    a_rounded[t].assign(model.a.begin(), model.a.end());
    b_rounded[t].assign(model.b.begin(), model.b.end());
  }
  mppi::CpuBackend<LinearModel<nx, nu>, ZeroCost> backend(model, {}, 64, T, static_cast<float>(dt), 1);
  const mppi::AncillaryWeights w{{1.f, 1.f, 0.2f, 0.2f}, {0.1f, 0.1f}, 2.f};
  const Matrix expect = riccati_oracle(a_rounded, b_rounded, diagonal({1, 1, 0.2, 0.2}), diagonal({0.1, 0.1}),
                                       diagonal({2, 2, 0.4, 0.4}), nx, nu);
  const double scale = max_abs(expect);
  std::vector<float> states((T + 1) * nx), gains(T * nu * nx);
  std::string why;

  SECTION("along the origin") {
    // At x = 0, u = 0 each perturbed lane's result is a_ij (+-h) or b_ic (+-h), rounded once,
    // and the divisor is exact: the Jacobians are the model's A and B to 2^-24 relative. The
    // gains then agree to ~1e-7 times the problem's conditioning; 1e-5 of the largest gain
    // leaves room, and a wrong index or time step is off by O(0.1).
    const std::vector<float> zero_x(nx, 0.f), zero_u(T * nu, 0.f);
    REQUIRE(backend.ancillary_gains(zero_x, zero_u, w, states, gains, &why));
    for (std::size_t i = 0; i < gains.size(); ++i) CHECK(std::fabs(gains[i] - expect[i]) <= 1e-5 * scale);
  }

  SECTION("along a moving plan") {
    const std::vector<float> x0{0.5f, -1.f, 1.f, 0.2f};
    std::vector<float> nominal(T * nu);
    for (int t = 0; t < T; ++t) {
      nominal[t * nu] = std::sin(0.1f * t);
      nominal[t * nu + 1] = -0.5f * std::cos(0.15f * t);
    }
    REQUIRE(backend.ancillary_gains(x0, nominal, w, states, gains, &why));
    // Away from the origin each float result of the step is rounded by up to half an ulp of
    // |x_{t+1}|, and central differences divide the difference of two by 2h: with |x| <= 10
    // here (ulp 9.5e-7) and 2h >= 9.8e-3 that is up to 1e-4 on Jacobian entries of size
    // dt^2/2 .. 1, ~2e-2 relative on the smallest (B's dt^2/2 = 5e-3). A linear system's
    // gains do not depend on the plan, so they must still match the oracle: to 1e-2 of the
    // largest gain (measured: 1.8e-3), far inside the O(0.1) of a wrong index or time step.
    float largest_state = 0.f;
    for (float v : states) largest_state = std::max(largest_state, std::fabs(v));
    REQUIRE(largest_state <= 10.f);
    for (std::size_t i = 0; i < gains.size(); ++i) CHECK(std::fabs(gains[i] - expect[i]) <= 1e-2 * scale);

    // Closed loop on the exact (double) system from a perturbed start:
    // u_t = u_nom_t + K_t (x_t - x_nom_t). The deviation obeys dx+ = (A + B K_t) dx, so it must
    // shrink; without feedback it does not (A has a double integrator).
    auto run = [&](bool feedback) {
      std::vector<double> x{x0[0] + 0.4, x0[1] - 0.3, x0[2] + 0.5, x0[3] - 0.2};
      for (int t = 0; t < T; ++t) {
        double u[nu];
        for (int c = 0; c < nu; ++c) {
          u[c] = nominal[t * nu + c];
          if (feedback)
            for (int i = 0; i < nx; ++i) u[c] += gains[(t * nu + c) * nx + i] * (x[i] - states[t * nx + i]);
        }
        std::vector<double> next(nx, 0.0);
        for (int i = 0; i < nx; ++i) {
          for (int k = 0; k < nx; ++k) next[i] += a_rounded[t][i * nx + k] * x[k];
          for (int c = 0; c < nu; ++c) next[i] += b_rounded[t][i * nu + c] * u[c];
        }
        x = next;
      }
      double d = 0;
      for (int i = 0; i < nx; ++i) d += std::pow(x[i] - states[T * nx + i], 2);
      return std::sqrt(d);
    };
    const double start = std::sqrt(0.4 * 0.4 + 0.3 * 0.3 + 0.5 * 0.5 + 0.2 * 0.2);
    const double open_loop = run(false), closed_loop = run(true);
    CHECK(open_loop > start);
    CHECK(closed_loop < 0.05 * start);
  }
}

TEST_CASE("CpuBackend::ancillary_gains: the kinematic bicycle tracks its plan from an offset start",
          "[lqr][mppi]") {
  // A left turn at 5 m/s (steady speed: throttle = v c / a_max = 0.25); the car starts 0.5 m to
  // the side, 0.1 rad off in heading and 0.5 m/s slow. The plant is the model itself, stepped
  // one lane at a time, with the feedback clamped to the control limits as the controller
  // clamps its controls.
  const mppi::KinematicBicycle model;
  using namespace mppi::state;
  constexpr int nx = mppi::KinematicBicycle::kNx, nu = mppi::KinematicBicycle::kNu, T = 100;
  const float dt = 0.02f;
  mppi::CpuBackend<mppi::KinematicBicycle, ZeroCost> backend(model, {}, 64, T, dt, 1);
  const std::vector<float> x0{0.f, 0.f, 0.f, 5.f, 0.f, 0.f, 0.f};
  std::vector<float> nominal(T * nu);
  for (int t = 0; t < T; ++t) nominal[t * nu] = 0.2f, nominal[t * nu + 1] = 0.25f;
  const mppi::AncillaryWeights w{{1.f, 1.f, 1.f, 1.f, 0.f, 0.f, 0.f}, {0.1f, 0.1f}, 10.f};
  std::vector<float> states((T + 1) * nx), gains(T * nu * nx);
  std::string why;
  REQUIRE(backend.ancillary_gains(x0, nominal, w, states, gains, &why));
  // Distance from the plan in x, y, yaw and speed (vy, yaw rate and roll follow from them).
  auto deviation = [&](const std::vector<float>& x, int t) {
    double d = 0;
    for (int i : {kX, kY, kYaw, kVx}) d += std::pow(x[i] - states[t * nx + i], 2);
    return std::sqrt(d);
  };
  auto run = [&](bool feedback) {
    std::vector<float> x = x0;
    x[kY] += 0.5f, x[kYaw] += 0.1f, x[kVx] -= 0.5f;
    for (int t = 0; t < T; ++t) {
      float u[nu];
      for (int c = 0; c < nu; ++c) {
        double v = nominal[t * nu + c];
        if (feedback)
          for (int i = 0; i < nx; ++i) v += gains[(t * nu + c) * nx + i] * (x[i] - states[t * nx + i]);
        u[c] = static_cast<float>(std::clamp(v, -1.0, 1.0));
      }
      model.step<1>(mppi::Batch<nx, 1>{x.data()}, mppi::ConstBatch<nu, 1>{u}, dt, nullptr);
    }
    return deviation(x, T);
  };
  std::vector<float> start = x0;
  start[kY] += 0.5f, start[kYaw] += 0.1f, start[kVx] -= 0.5f;
  const double initial = deviation(start, 0), open_loop = run(false), closed_loop = run(true);
  INFO("initial " << initial << ", after 2 s: open loop " << open_loop << ", closed loop " << closed_loop);
  CHECK(open_loop > initial);
  CHECK(closed_loop < 0.2 * initial);
}

TEST_CASE("ancillary gains: bad input is refused by name", "[lqr][mppi]") {
  using Backend = mppi::CpuBackend<mppi::test::DoubleIntegrator, mppi::test::QuadraticCost>;
  constexpr int T = 10;
  Backend backend({}, {}, 64, T, 0.1f, 1);
  std::vector<float> x0{0.f, 1.f}, nominal(T), states((T + 1) * 2), gains(T * 2);
  const mppi::AncillaryWeights w;
  std::string why;
  REQUIRE(backend.ancillary_gains(x0, nominal, w, states, gains, &why));
  auto refused = [&](std::span<const float> x, std::span<const float> u, const mppi::AncillaryWeights& ww,
                     std::span<float> s, std::span<float> g) {
    why.clear();
    const bool ok = backend.ancillary_gains(x, u, ww, s, g, &why);
    return !ok && !why.empty();
  };
  SECTION("sizes") {
    std::vector<float> x3(3), u9(T - 1), s_short(T * 2), g_long(T * 2 + 1);
    CHECK(refused(x3, nominal, w, states, gains));
    CHECK_THAT(why, Catch::Contains("x0"));
    CHECK(refused(x0, u9, w, states, gains));
    CHECK_THAT(why, Catch::Contains("nominal"));
    CHECK(refused(x0, nominal, w, s_short, gains));
    CHECK_THAT(why, Catch::Contains("states_out"));
    CHECK(refused(x0, nominal, w, states, g_long));
    CHECK_THAT(why, Catch::Contains("gains_out"));
  }
  SECTION("non-finite values") {
    x0[1] = std::numeric_limits<float>::quiet_NaN();
    CHECK(refused(x0, nominal, w, states, gains));
    CHECK_THAT(why, Catch::Contains("x0[1]"));
    x0[1] = 0.f;
    nominal[4] = std::numeric_limits<float>::infinity();
    CHECK(refused(x0, nominal, w, states, gains));
    CHECK_THAT(why, Catch::Contains("nominal[4]"));
  }
  SECTION("weights") {
    CHECK(refused(x0, nominal, {{1.f, 1.f, 1.f}, {}, 1.f}, states, gains));
    CHECK_THAT(why, Catch::Contains("q_diag"));
    CHECK(refused(x0, nominal, {{}, {0.f}, 1.f}, states, gains));
    CHECK_THAT(why, Catch::Contains("r_diag"));
    CHECK(refused(x0, nominal, {{-1.f, 1.f}, {}, 1.f}, states, gains));
    CHECK_THAT(why, Catch::Contains("q_diag[0]"));
    CHECK(refused(x0, nominal, {{}, {}, -1.f}, states, gains));
    CHECK_THAT(why, Catch::Contains("terminal_scale"));
  }
  SECTION("a backend that cannot linearise says so") {
    struct NoModel final : mppi::Backend {
      mppi::RolloutShape s{1, 64, T, 2, 1};
      const char* name() const override { return "opaque"; }
      const mppi::RolloutShape& shape() const override { return s; }
      void rollout(std::span<const float>, std::span<const float>, std::span<float>) override {}
    } opaque;
    CHECK_FALSE(opaque.ancillary_gains(x0, nominal, w, states, gains, &why));
    CHECK(why == "opaque backend cannot linearise its model");
  }
  SECTION("solve_lqr names its arguments") {
    mppi::LqrWorkspace ws;
    const std::vector<double> a(4 * T), b(2 * T), q{1, 1}, r{1};
    std::vector<double> g(2 * T);
    CHECK_FALSE(mppi::solve_lqr<double>({T, 2, 1, std::span(a).first(3), b, q, r, q}, ws, g, &why));
    CHECK_THAT(why, Catch::Contains("a has 3"));
    CHECK_FALSE(mppi::solve_lqr<double>({T, 2, 1, a, b, q, r, q}, ws, std::span(g).first(5), &why));
    CHECK_THAT(why, Catch::Contains("gains"));
    const std::vector<double> r_bad{0.0};
    CHECK_FALSE(mppi::solve_lqr<double>({T, 2, 1, a, b, q, r_bad, q}, ws, g, &why));
    CHECK_THAT(why, Catch::Contains("r is not positive definite"));
    std::vector<double> a_nan = a;
    a_nan[4 * 3 + 1] = std::numeric_limits<double>::quiet_NaN();
    CHECK_FALSE(mppi::solve_lqr<double>({T, 2, 1, a_nan, b, q, r, q}, ws, g, &why));
    CHECK_THAT(why, Catch::Contains("t = 3"));
  }
}
