// The UKF against the closed-form Kalman filter on linear systems (where the unscented
// transform is exact), the joint-state UKF on a nonlinear system with known parameters, and
// the nearest-positive-definite projection against its closed form.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "sysid/alm_ukf.hpp"
#include "sysid/ukf.hpp"

using namespace mppi::sysid;

TEST_CASE("UKF equals the Kalman filter on a linear system, with noise means", "[sysid][ukf]") {
  const double dt = 0.1;
  Mat A(2, 2), B(2, 1), C(1, 2);
  A << 1, dt, -0.2 * dt, 1 - 0.05 * dt;  // damped oscillator
  B << 0, dt;
  C << 1, 0;
  Mat Q(2, 2), R(1, 1);
  Q << 1e-4, 2e-5, 2e-5, 4e-4;
  R << 0.01;
  Vec q(2), r(1);
  q << 0.001, -0.002;
  r << 0.05;

  for (double alpha : {1e-3, 0.5, 1.0}) {
    UkfSettings s;
    s.alpha = alpha;
    Ukf ukf(2, [&](const Vec& x, const Vec& u) -> Vec { return A * x + B * u; },
            [&](const Vec& x, const Vec&) -> Vec { return C * x; }, s);
    Vec x0(2);
    x0 << 0.5, 0;
    Mat P0 = Mat::Identity(2, 2) * 0.3;
    ukf.reset(x0, P0);
    ukf.set_process_noise(q, Q);
    ukf.set_measurement_noise(r, R);
    // Closed form.
    Vec xk = x0;
    Mat Pk = P0;
    std::mt19937 rng(7);
    std::normal_distribution<double> n01;
    Vec truth(2);
    truth << 1.0, 0.0;
    for (int k = 0; k < 200; ++k) {
      Vec u(1);
      u << std::sin(0.05 * k);
      truth = A * truth + B * u + q;
      truth(0) += 0.01 * n01(rng);
      Vec y = C * truth + r;
      y(0) += 0.1 * n01(rng);
      ukf.predict(u);
      ukf.update(y, u);
      xk = A * xk + B * u + q;
      Pk = A * Pk * A.transpose() + Q;
      const Mat S = C * Pk * C.transpose() + R;
      const Mat K = Pk * C.transpose() * S.inverse();
      xk += K * (y - C * xk - r);
      Pk = (Mat::Identity(2, 2) - K * C) * Pk;
      INFO("alpha " << alpha << " step " << k);
      REQUIRE((ukf.x() - xk).norm() < 1e-8 * (1 + xk.norm()));
      REQUIRE((ukf.P() - Pk).norm() < 1e-8 * (1 + Pk.norm()));
    }
  }
}

TEST_CASE("UKF skips missing measurement entries like a KF with the measured rows only", "[sysid][ukf]") {
  Mat A = Mat::Identity(2, 2), C = Mat::Identity(2, 2);
  Ukf ukf(2, [&](const Vec& x, const Vec&) -> Vec { return A * x; },
          [&](const Vec& x, const Vec&) -> Vec { return C * x; });
  ukf.reset(Vec::Zero(2), Mat::Identity(2, 2));
  ukf.set_process_noise(Vec::Zero(2), Mat::Zero(2, 2));
  ukf.set_measurement_noise(Vec::Zero(2), Mat::Identity(2, 2));
  Vec y(2);
  y << NAN, 2.0;
  ukf.update(y, Vec());
  // Second component: prior var 1, meas var 1 -> mean 1, var 0.5; first untouched.
  CHECK(ukf.x()(0) == Approx(0).margin(1e-12));
  CHECK(ukf.x()(1) == Approx(1.0));
  CHECK(ukf.P()(0, 0) == Approx(1.0));
  CHECK(ukf.P()(1, 1) == Approx(0.5));
}

TEST_CASE("nearest positive definite matrix: closed form under rotation", "[sysid][ukf]") {
  const double th = 0.3;
  Mat Rot(2, 2);
  Rot << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
  Mat D = Mat::Zero(2, 2);
  D(0, 0) = 2.0;
  D(1, 1) = -0.5;
  const Mat A = Rot * D * Rot.transpose();
  Mat Dc = D;
  Dc(1, 1) = 1e-6;
  const Mat expected = Rot * Dc * Rot.transpose();
  CHECK((nearest_positive_definite(A, 1e-6) - expected).norm() < 1e-12);
  // Already PD: unchanged; asymmetric: symmetrised.
  Mat B(2, 2);
  B << 2, 0.4, 0.2, 1;
  Mat Bs(2, 2);
  Bs << 2, 0.3, 0.3, 1;
  CHECK((nearest_positive_definite(B, 1e-6) - Bs).norm() < 1e-12);
}

TEST_CASE("joint-state UKF identifies a nonlinear pendulum's parameters", "[sysid][ukf]") {
  // theta'' = -a sin(theta) - c theta' + u, measured angle only; true a = 9.81/0.5, c = 0.6.
  const double dt = 0.01, a_true = 19.62, c_true = 0.6;
  auto f = [dt](const Vec& x, const Vec& p, const Vec& u) -> Vec {
    Vec out(2);
    out(0) = x(0) + dt * x(1);
    out(1) = x(1) + dt * (-p(0) * std::sin(x(0)) - p(1) * x(1) + u(0));
    return out;
  };
  auto h = [](const Vec& x, const Vec&, const Vec&) -> Vec { return x.head(1); };
  std::mt19937 rng(3);
  std::normal_distribution<double> n01;
  for (bool adaptive : {false, true}) {
    JointModel m{2, 2, 1, f, h};
    JointFilterSettings s;
    s.adaptive = adaptive;
    s.alm.window = 400;
    s.alm.estimate_process = false;  // Q^ and R^ together are not separable (test_alm_ukf.cpp)
    Vec x0 = Vec::Zero(2), p0(2);
    p0 << 12.0, 0.2;  // 40% and 67% off
    Mat Pp0(2, 2);
    Pp0 << 25.0, 0, 0, 0.25;
    Mat R = Mat::Identity(1, 1) * 1e-4;
    Vec pstd(2);
    pstd << 1e-3, 1e-4;
    JointStateFilter filt(m, s, x0, Mat::Identity(2, 2) * 0.1, p0, Pp0, Mat::Identity(2, 2) * 1e-8, R, pstd);
    Vec x(2), p(2);
    x << 0.8, 0;
    p << a_true, c_true;
    Vec u(1), u_prev(1);
    u_prev << 0;
    for (int k = 0; k < 3000; ++k) {
      u << 2.0 * std::sin(0.7 * k * dt) * std::sin(0.13 * k * dt);
      x = f(x, p, u_prev);
      Vec y = x.head(1);
      y(0) += 0.01 * n01(rng);
      filt.step(u_prev, y, u);
      u_prev = u;
    }
    INFO("adaptive " << adaptive << ": a " << filt.params()(0) << " c " << filt.params()(1));
    CHECK(filt.params()(0) == Approx(a_true).epsilon(0.02));
    CHECK(filt.params()(1) == Approx(c_true).epsilon(0.05));
  }
}
