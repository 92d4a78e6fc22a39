// The single-track model with Pacejka tyres: derivatives against numpy values and against an
// independent double-precision reference written here from the paper's equations; batched
// float stepping against the scalar path; physical checks (symmetry, coast-down closed form,
// kinematic limit, steady speed) and explicit-Euler stability at the controller's 0.02 s.
#include <catch2/catch.hpp>

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <complex>
#include <random>
#include <string>
#include <vector>

#include "dynamics/single_track.hpp"
#include "mppi/concepts.hpp"
#include "test_data.hpp"

using mppi::SingleTrack;
using mppi::SingleTrackParams;
namespace st = mppi::state;

static_assert(mppi::VehicleDynamics<SingleTrack>);

namespace {

using State = std::array<double, 9>;

// ---- Independent reference, from the paper (Velenis 2010 equations, Magic Formula) --------
// Written without the model's helpers: complex numbers for the frame rotations, the normal
// load solved from the pitch moment balance about the rear contact point.
// The rear tyre has B, C, D multiplied by rear_tyre_{B,C,D}_scale (E, Sh, Sv shared).
double ref_mu(const SingleTrackParams& p, double s, bool rear) {
  const auto& t = p.tyre;
  const double B = rear ? t.B * p.rear_tyre_B_scale : t.B, C = rear ? t.C * p.rear_tyre_C_scale : t.C,
               D = rear ? t.D * p.rear_tyre_D_scale : t.D;
  const double x = s - t.Sh;
  return D * std::sin(C * std::atan(B * x - t.E * (B * x - std::atan(x)))) + t.Sv;
}

// Friction coefficient vector (tyre frame) of a tyre moving at `v` with rim speed `rim`:
// -(s/|s|) mu(|s|) tanh(|s|/eps) with s = (v - rim, v_y) / max(|rim|, v_floor).
std::complex<double> ref_friction(const SingleTrackParams& p, std::complex<double> v, double rim, bool rear) {
  const double den = std::max(std::abs(rim), p.slip_speed_floor_mps);
  const std::complex<double> slip((v.real() - rim) / den, v.imag() / den);
  const double s = std::abs(slip);
  if (s == 0) return 0.0;
  return -slip / s * ref_mu(p, s, rear) * std::tanh(s / p.slip_blend);
}

State ref_rhs(const SingleTrackParams& p, const State& x, double steer, double throttle) {
  const double m = p.mass_kg, g = p.gravity_mps2, lf = p.cg_to_front_axle_m,
               lr = p.cg_to_rear_axle_m, h = p.cg_height_m, R = p.wheel_radius_m;
  const double vx = x[3], vy = x[4], r = x[5], wf = x[7], wr = x[8];
  const double delta = std::clamp(steer, -1.0, 1.0) * p.max_steer_rad;
  const std::complex<double> to_wheel = std::polar(1.0, -delta), to_body = std::polar(1.0, delta);
  const std::complex<double> v_front = std::complex<double>(vx, vy + r * lf) * to_wheel;
  const std::complex<double> v_rear(vx, vy - r * lr);
  const std::complex<double> mu_front = ref_friction(p, v_front, wf * R, false);
  const std::complex<double> mu_rear = ref_friction(p, v_rear, wr * R, true);
  // Pitch moment about the rear contact: Ffz (lf + lr) - m g lr + h Fx_total = 0 with
  // Fx_total = Re(mu_front e^{i delta}) Ffz + Re(mu_rear) (m g - Ffz).
  const double front_x_per_load = (mu_front * to_body).real();
  double ffz = (m * g * lr - h * mu_rear.real() * m * g) /
               (lf + lr + h * front_x_per_load - h * mu_rear.real());
  ffz = std::clamp(ffz, 0.0, m * g);
  const double frz = m * g - ffz;
  const std::complex<double> f_front_wheel = mu_front * ffz, f_rear = mu_rear * frz;
  const std::complex<double> f_front_body = f_front_wheel * to_body;
  // The motor turns with the axles' wheel speeds weighted by their shares of its torque.
  const double front_share = p.front_drive_share, rear_share = 1 - front_share;
  const double torque = p.stall_torque_Nm * (throttle - (front_share * wf + rear_share * wr) * R / p.no_load_speed_mps);
  const double resist = -p.rolling_resistance * m * g * std::tanh(vx / p.rolling_resistance_speed_mps) -
                        p.aero_drag_kgpm * vx * std::abs(vx);
  State dx{};
  dx[0] = vx * std::cos(x[2]) - vy * std::sin(x[2]);
  dx[1] = vx * std::sin(x[2]) + vy * std::cos(x[2]);
  dx[2] = r;
  dx[3] = (f_front_body.real() + f_rear.real() + resist) / m + vy * r;
  dx[4] = (f_front_body.imag() + f_rear.imag()) / m - vx * r;
  dx[5] = (f_front_body.imag() * lf - f_rear.imag() * lr) / p.yaw_inertia_kgm2;
  dx[6] = 0;
  dx[7] = (front_share * torque - f_front_wheel.real() * R) / p.front_wheel_inertia_kgm2;
  dx[8] = (rear_share * torque - f_rear.real() * R) / p.rear_wheel_inertia_kgm2;
  return dx;
}

// One lane, float, through the batched step<1>.
std::array<float, 9> step1(const SingleTrack& m, std::array<float, 9> x, float steer, float throttle,
                           float dt, int steps = 1) {
  const float u[2] = {steer, throttle};
  for (int i = 0; i < steps; ++i)
    m.step<1>(mppi::Batch<9, 1>{x.data()}, mppi::ConstBatch<2, 1>{u}, dt, nullptr);
  return x;
}

std::array<float, 9> initial(const SingleTrack& m, float vx, float vy = 0, float r = 0) {
  std::array<float, 9> x{};
  m.init_state(mppi::VehicleState{0, 0, 0, vx, vy, r, 0}, x.data());
  return x;
}

bool all_finite(const std::array<float, 9>& x) {
  for (float v : x)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

TEST_CASE("Single-track derivatives at nontrivial states: numpy and independent reference",
          "[physics][single_track]") {
  const SingleTrackParams p;
  const SingleTrack model(p);
  // numpy float64 implementation of the same paper equations and regularisation, default
  // parameters. States: x y yaw vx vy r roll omega_f omega_r; controls: steer throttle.
  struct Case {
    const char* what;
    State x;
    double u[2];
    State expected;
  };
  const Case cases[] = {
      {"cornering left, accelerating",
       {1.0, -2.0, 0.7, 8.0, 0.4, 1.2, 0, 80.0, 84.0}, {0.5, 0.4},
       {5.86105042338, 5.45967837282, 1.2, -0.302401435659, -8.85476244549, 7.49538816749, 0,
        13.6099627996, 11.7031771895}},
      {"drift: counter-steer, rear spinning",
       {0, 0, -1.3, 6.0, -2.5, 2.0, 0, 60.0, 95.0}, {-0.8, 0.9},
       {-0.803902491795, -6.45009618406, 2, -2.27882767918, -8.29322562008, -15.3718958197, 0,
        29.88181423, -57.8154111547}},
      {"hard braking, rear nearly locked",
       {5, 3, 2.5, 10.0, 0.3, -0.5, 0, 100.0, 20.0}, {0.2, -1.0},
       {-8.1909777987, 5.74437835638, -0.5, -6.57661314112, 5.65244579578, 7.34191244644, 0,
        15.5602957429, 14.2431937236}},
      {"below the slip speed floor, full lock",
       {0, 0, 0, 1.2, 0.1, 0.3, 0, 10.0, 15.0}, {1.0, 0.3},
       {1.2, 0.1, 0.3, -0.0384348726589, 0.0477328345452, 4.65816825823, 0, 34.8645575646,
        -15.4039710415}},
      {"reversing, braking",
       {0, 0, 3.0, -2.0, 0.2, -0.4, 0, -25.0, -15.0}, {-0.3, -0.6},
       {1.95176099159, -0.48023851544, -0.4, 1.75264508509, -1.57602226133, 11.2121409666, 0,
        64.4068558246, -256.779394172}},
  };
  for (const auto& c : cases) {
    INFO(c.what);
    State dx{};
    model.derivatives(c.x.data(), c.u, dx.data());
    const State ref = ref_rhs(p, c.x, c.u[0], c.u[1]);
    for (int i = 0; i < 9; ++i) {
      INFO("component " << i);
      CHECK(dx[i] == Approx(c.expected[i]).epsilon(1e-9).margin(1e-9));
      CHECK(ref[i] == Approx(c.expected[i]).epsilon(1e-9).margin(1e-9));
    }
  }
}

TEST_CASE("Single-track derivatives match the reference at random states", "[physics][single_track]") {
  SingleTrackParams p;
  SECTION("one tyre on both axles") {}
  SECTION("per-axle tyres: the rear's B, C, D scaled") {
    p.rear_tyre_B_scale = 1.7;
    p.rear_tyre_C_scale = 0.8;
    p.rear_tyre_D_scale = 1.2;
  }
  SECTION("four-wheel drive: 40 % of the motor torque on the front axle") { p.front_drive_share = 0.4; }
  const SingleTrack model(p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int k = 0; k < 500; ++k) {
    const double vx = 10 + 12 * U(rng);
    const State x = {U(rng), U(rng), 4 * U(rng), vx, 2 * U(rng), 3 * U(rng), 0,
                     vx / p.wheel_radius_m * (1 + 0.5 * U(rng)) + 20 * U(rng),
                     vx / p.wheel_radius_m * (1 + 0.5 * U(rng)) + 20 * U(rng)};
    const double u[2] = {U(rng), U(rng)};
    State dx{};
    model.derivatives(x.data(), u, dx.data());
    const State ref = ref_rhs(p, x, u[0], u[1]);
    for (int i = 0; i < 9; ++i) REQUIRE(dx[i] == Approx(ref[i]).epsilon(1e-9).margin(1e-9));
  }
}

// Closed form: a launch on Coulomb tyres (C = 1, B huge: mu = D at any real slip), no load
// transfer (h = 0), no resistances, a motor far stronger than the grip. Rear-wheel drive spins the
// rear wheels only: the rear axle's static load m g l_f / L pushes the car and the rolling front
// wheels, a = D g (l_f / L) m / (m + I_f / R^2). With any share of the torque on the front axle
// both axles spin: a = D g.
TEST_CASE("Single-track drive split: traction-limited launch, rear- against four-wheel drive",
          "[physics][single_track]") {
  SingleTrackParams p;
  p.tyre = {1000.0, 1.0, 0.6, 0.0, 0.0, 0.0};
  p.cg_height_m = 0;
  p.rolling_resistance = 0;
  p.aero_drag_kgpm = 0;
  p.stall_torque_Nm = 400;
  p.no_load_speed_mps = 200;
  const double g = p.gravity_mps2, D = p.tyre.D;
  auto launch_accel = [&](double share) {
    p.front_drive_share = share;
    const SingleTrack m(p);
    auto x = step1(m, initial(m, 2.0f), 0.f, 1.f, 0.002f, 250);  // 0.5 s: the wheels spin up
    const float v0 = x[st::kVx];
    x = step1(m, x, 0.f, 1.f, 0.002f, 250);
    return (x[st::kVx] - v0) / 0.5;
  };
  const double rolling_front_kg = p.front_wheel_inertia_kgm2 / (p.wheel_radius_m * p.wheel_radius_m);
  CHECK(launch_accel(0.0) == Approx(D * g * p.cg_to_front_axle_m / p.wheelbase_m() * p.mass_kg /
                                    (p.mass_kg + rolling_front_kg)).epsilon(0.02));
  CHECK(launch_accel(0.5) == Approx(D * g).epsilon(0.02));
  CHECK(launch_accel(0.25) == Approx(D * g).epsilon(0.02));
  p.front_drive_share = 1.2;
  std::string why;
  CHECK_FALSE(p.is_valid(&why));
  CHECK(why.find("front_drive_share") != std::string::npos);
}

TEST_CASE("Single-track forces: static loads, load transfer, free rolling", "[physics][single_track]") {
  const SingleTrackParams p;
  const SingleTrack model(p);
  const double mg = 21.88 * 9.81;
  // Free rolling (omega = v / R, no slip): no friction, static loads m g l_r / L and m g l_f / L.
  const State x0 = {0, 0, 0, 8.0, 0, 0, 0, 8.0 / 0.0975, 8.0 / 0.0975};
  const double u0[2] = {0, 0};
  const auto f0 = model.forces(x0.data(), u0);
  CHECK(f0.front_fz_N == Approx(mg * 0.23 / 0.57).epsilon(1e-12));  // 86.6066 N
  CHECK(f0.rear_fz_N == Approx(mg * 0.34 / 0.57).epsilon(1e-12));   // 128.0314 N
  CHECK(f0.front_fx_N == 0.0);
  CHECK(f0.rear_fy_N == 0.0);
  // Rear wheel driving (faster than the ground): forward force, load moves to the rear by
  // h f_Rx / L (pitch moment balance with only the rear force).
  State xa = x0;
  xa[8] *= 1.3;
  const auto fa = model.forces(xa.data(), u0);
  CHECK(fa.rear_fx_N > 10);
  CHECK(fa.rear_fz_N - mg * 0.34 / 0.57 == Approx(0.12 * fa.rear_fx_N / 0.57).epsilon(1e-9));
  CHECK(fa.front_fz_N + fa.rear_fz_N == Approx(mg));
  // Front wheel braking: load moves to the front.
  State xb = x0;
  xb[7] *= 0.5;
  const auto fb = model.forces(xb.data(), u0);
  CHECK(fb.front_fx_N < -10);
  CHECK(fb.front_fz_N > mg * 0.23 / 0.57 + 1);
}

TEST_CASE("Single-track batched step<64> equals the scalar step and Euler in double",
          "[physics][single_track]") {
  const SingleTrackParams p;
  const SingleTrack model(p);
  constexpr int W = 64;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> U(-1, 1);
  std::vector<float> xb(9 * W), ub(2 * W);
  std::vector<std::array<float, 9>> lanes(W);
  std::vector<std::array<float, 2>> controls(W);
  for (int j = 0; j < W; ++j) {
    const float vx = 8 + 10 * U(rng);
    lanes[j] = {30 * U(rng), 30 * U(rng), 50 * U(rng), vx, 2 * U(rng), 3 * U(rng), 0,
                vx / 0.0975f * (1 + 0.3f * U(rng)), vx / 0.0975f * (1 + 0.3f * U(rng))};
    controls[j] = {U(rng), U(rng)};
    for (int i = 0; i < 9; ++i) xb[i * W + j] = lanes[j][i];
    for (int i = 0; i < 2; ++i) ub[i * W + j] = controls[j][i];
  }
  const float dt = 0.02f;
  model.step<W>(mppi::Batch<9, W>{xb.data()}, mppi::ConstBatch<2, W>{ub.data()}, dt, nullptr);
  for (int j = 0; j < W; ++j) {
    const auto scalar = step1(model, lanes[j], controls[j][0], controls[j][1], dt);
    State xd{}, dx{};
    for (int i = 0; i < 9; ++i) xd[i] = lanes[j][i];
    const double ud[2] = {controls[j][0], controls[j][1]};
    model.derivatives(xd.data(), ud, dx.data());
    for (int i = 0; i < 9; ++i) {
      INFO("lane " << j << " component " << i);
      const double scale = std::max({1.0, std::abs(xd[i]), std::abs(dx[i] * dt)});
      // Vectorised and scalar code may contract to FMA differently: a few ulp apart.
      CHECK(std::abs(xb[i * W + j] - scalar[i]) <= 1e-5 * scale);
      // Float fast math (~1e-7 relative) vs double libm.
      CHECK(std::abs(xb[i * W + j] - (xd[i] + dt * dx[i])) <= 2e-5 * scale);
    }
  }
}

TEST_CASE("Single-track straight line stays straight, steering is mirror-symmetric",
          "[physics][single_track]") {
  const SingleTrack model;
  // Straight: steer 0, no lateral velocity or yaw rate -> no lateral force, exactly.
  auto x = step1(model, initial(model, 3.f), 0.f, 0.6f, 0.02f, 500);
  CHECK(x[st::kY] == 0.f);
  CHECK(x[st::kYaw] == 0.f);
  CHECK(x[st::kVy] == 0.f);
  CHECK(x[st::kYawRate] == 0.f);
  CHECK(x[st::kVx] > 9.f);
  // Mirror: (vy, r, steer) -> -(vy, r, steer) mirrors y, yaw, vy, r; x, vx, wheels unchanged.
  const auto a = step1(model, initial(model, 8.f, 0.5f, 0.8f), 0.6f, 0.4f, 0.02f, 150);
  const auto b = step1(model, initial(model, 8.f, -0.5f, -0.8f), -0.6f, 0.4f, 0.02f, 150);
  REQUIRE(std::abs(a[st::kYaw]) > 1.f);  // it did turn
  for (int i : {st::kX, st::kVx, SingleTrack::kOmegaFront, SingleTrack::kOmegaRear})
    CHECK(b[i] == Approx(a[i]).epsilon(1e-5).margin(1e-5));
  for (int i : {st::kY, st::kYaw, st::kVy, st::kYawRate})
    CHECK(b[i] == Approx(-a[i]).epsilon(1e-5).margin(1e-5));
}

TEST_CASE("Single-track coast-down: closed form without motor, monotone with engine braking",
          "[physics][single_track]") {
  // No motor torque: m_eff dv/dt = -(a + c v^2) with a = c_rr m g (tanh(v/0.5) = 1 above 5 m/s),
  // c = c_d and m_eff = m + (I_f + I_r)/R^2 (the wheels spin down with the car). Closed form:
  // v(t) = sqrt(a/c) tan(atan(v0 sqrt(c/a)) - t sqrt(a c)/m_eff).
  SingleTrackParams p;
  p.stall_torque_Nm = 0;
  const SingleTrack free_wheels(p);
  const double a = p.rolling_resistance * p.mass_kg * p.gravity_mps2, c = p.aero_drag_kgpm;
  const double m_eff = p.mass_kg + (p.front_wheel_inertia_kgm2 + p.rear_wheel_inertia_kgm2) /
                                       (p.wheel_radius_m * p.wheel_radius_m);
  // Compare after the wheels have settled to their quasi-steady slip (they lead the ground by
  // ~0.1 m/s while being dragged down; from the no-slip start that takes ~0.5 s).
  auto x = step1(free_wheels, initial(free_wheels, 10.f), 0.f, 0.f, 0.002f, 500);  // 1 s
  const double v0 = x[st::kVx], t = 3;
  const double v_expected = std::sqrt(a / c) * std::tan(std::atan(v0 * std::sqrt(c / a)) - t * std::sqrt(a * c) / m_eff);
  x = step1(free_wheels, x, 0.f, 0.f, 0.002f, 1500);
  CHECK(v0 == Approx(9.48).margin(0.01));
  CHECK(x[st::kVx] == Approx(v_expected).epsilon(1e-3));  // 8.10 m/s
  // Default drivetrain at zero throttle: the speed falls every step (engine braking).
  const SingleTrack model;
  auto y = initial(model, 12.f);
  for (int k = 0; k < 300; ++k) {
    const float before = y[st::kVx];
    y = step1(model, y, 0.f, 0.f, 0.02f);
    REQUIRE(y[st::kVx] < before);
  }
  CHECK(y[st::kVx] < 6.f);
}

TEST_CASE("Single-track small steering approaches the kinematic bicycle", "[physics][single_track]") {
  // With the paper's tyres at small slip, front and rear cornering stiffness are proportional
  // to the static loads (m g l_r / L, m g l_f / L): a neutral-steer car, so at small lateral
  // acceleration the yaw rate is the kinematic v tan(delta) / L. Free-rolling wheels (no motor,
  // no resistance) so that no longitudinal force shifts load or uses up grip.
  SingleTrackParams p;
  p.stall_torque_Nm = 0;
  p.rolling_resistance = 0;
  p.aero_drag_kgpm = 0;
  const SingleTrack model(p);
  for (float steer : {0.05f, -0.1f}) {
    INFO("steer " << steer);
    const auto x = step1(model, initial(model, 4.f), steer, 0.f, 0.002f, 5000);  // 10 s
    const double delta = steer * 0.38;
    CHECK(x[st::kYawRate] / x[st::kVx] == Approx(std::tan(delta) / 0.57).epsilon(3e-3));
    CHECK(x[st::kVx] == Approx(3.8).margin(0.2));  // a little speed goes into the tyre slip
  }
}

TEST_CASE("Single-track explicit Euler at 0.02 s: stability and accuracy", "[physics][single_track]") {
  const SingleTrack model;
  SECTION("rest to top speed: steady speed of the drivetrain, no overshoot") {
    auto x = initial(model, 0.f);
    float v_max = 0;
    for (int k = 0; k < 3000; ++k) {  // 60 s
      x = step1(model, x, 0.f, 1.f, 0.02f);
      REQUIRE(all_finite(x));
      v_max = std::max(v_max, x[st::kVx]);
    }
    // numpy, same equations, dt 0.002 s for 60 s: 19.5966 m/s at throttle 1.
    CHECK(x[st::kVx] == Approx(19.5966).epsilon(5e-4));
    CHECK(v_max <= x[st::kVx] * 1.001f);
    CHECK(x[st::kY] == 0.f);
  }
  SECTION("step steer at speed: bounded, close to the 500 Hz solution") {
    const auto start = initial(model, 10.f);
    const auto coarse = step1(model, start, 1.f, 0.5f, 0.02f, 150);
    const auto fine = step1(model, start, 1.f, 0.5f, 0.002f, 1500);
    REQUIRE(all_finite(coarse));
    CHECK(std::abs(coarse[st::kYawRate]) < 8.f);
    CHECK(coarse[st::kYawRate] == Approx(fine[st::kYawRate]).epsilon(0.05));
    CHECK(coarse[st::kVx] == Approx(fine[st::kVx]).epsilon(0.05));
    CHECK(coarse[st::kVy] == Approx(fine[st::kVy]).margin(0.1));
  }
  SECTION("random controls from random states: always finite and bounded") {
    constexpr int W = 64;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> U(-1, 1);
    std::vector<float> xb(9 * W), ub(2 * W);
    for (int j = 0; j < W; ++j) {
      const float vx = 8 + 10 * U(rng);
      const float lane[9] = {0, 0, 0, vx, 2 * U(rng), 2 * U(rng), 0, vx / 0.0975f * (1 + 0.3f * U(rng)),
                             vx / 0.0975f * (1 + 0.5f * U(rng))};
      for (int i = 0; i < 9; ++i) xb[i * W + j] = lane[i];
    }
    for (int t = 0; t < 200; ++t) {
      for (auto& v : ub) v = U(rng);
      model.step<W>(mppi::Batch<9, W>{xb.data()}, mppi::ConstBatch<2, W>{ub.data()}, 0.02f, nullptr);
    }
    for (int j = 0; j < W; ++j) {
      INFO("lane " << j);
      for (int i = 0; i < 9; ++i) REQUIRE(std::isfinite(xb[i * W + j]));
      CHECK(std::abs(xb[3 * W + j]) < 30.f);
      CHECK(std::abs(xb[4 * W + j]) < 15.f);
      CHECK(std::abs(xb[5 * W + j]) < 15.f);
    }
  }
}

TEST_CASE("Single-track Jacobian: explicit Euler at 0.02 s stays in its non-oscillating range",
          "[physics][single_track]") {
  // Largest decay rate -Re(lambda) of the body + wheel dynamics (vx, vy, r, omega_f, omega_r)
  // over sampled states, by central differences of derivatives(): lambda dt < 1 means Euler
  // neither oscillates nor diverges on any decaying mode (the slip floor is what bounds it).
  const SingleTrack model;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  const int idx[5] = {3, 4, 5, 7, 8};
  double worst = 0;
  for (int k = 0; k < 1500; ++k) {
    const bool slow = k % 2 == 0;  // half the samples at low speed, where it is stiffest
    const double vx = slow ? -1 + 5 * U(rng) : -2 + 22 * U(rng);
    State x = {0, 0, 0, vx, (slow ? 2 : 6) * (U(rng) - 0.5), (slow ? 4 : 8) * (U(rng) - 0.5), 0, 0, 0};
    for (int w : {7, 8})
      x[w] = slow ? -10 + 55 * U(rng) : vx / 0.0975 * (0.6 + 0.8 * U(rng));
    const double u[2] = {2 * U(rng) - 1, 2 * U(rng) - 1};
    Eigen::Matrix<double, 5, 5> J;
    for (int c = 0; c < 5; ++c) {
      State xp = x, xm = x, dp{}, dm{};
      const double h = 1e-6 * std::max(1.0, std::abs(x[idx[c]]));
      xp[idx[c]] += h;
      xm[idx[c]] -= h;
      model.derivatives(xp.data(), u, dp.data());
      model.derivatives(xm.data(), u, dm.data());
      for (int r = 0; r < 5; ++r) J(r, c) = (dp[idx[r]] - dm[idx[r]]) / (2 * h);
    }
    const Eigen::EigenSolver<Eigen::Matrix<double, 5, 5>> es(J, false);
    for (int i = 0; i < 5; ++i) worst = std::max(worst, -es.eigenvalues()[i].real());
  }
  INFO("largest decay rate " << worst << " 1/s");
  CHECK(worst * 0.02 < 1.0);
  CHECK(worst * 0.02 > 0.3);  // the wheel-slip mode is indeed fast: the check is meaningful
}

TEST_CASE("SingleTrack rejects invalid parameters and initialises rolling wheels",
          "[physics][single_track]") {
  SingleTrackParams p;
  p.mass_kg = -1;
  CHECK_THROWS_WITH(SingleTrack(p), Catch::Contains("mass_kg"));
  p = {};
  p.cg_height_m = 0.3;  // 2 h (D + Sv) = 0.68 > wheelbase: the load formula could divide by 0
  CHECK_THROWS_WITH(SingleTrack(p), Catch::Contains("cg_height_m"));
  p = {};
  p.rear_tyre_D_scale = 0;
  CHECK_THROWS_WITH(SingleTrack(p), Catch::Contains("rear_tyre_D_scale"));
  p = {};
  p.rear_tyre_C_scale = 1.8;  // rear C = 1.19 x 1.8 = 2.15: outside the Magic Formula's (0, 2)
  CHECK_THROWS_WITH(SingleTrack(p), Catch::Contains("rear tyre") && Catch::Contains("C"));
  p = {};
  p.rear_tyre_D_scale = 2.5;  // 2 h (2.5 D + Sv) = 0.63 > wheelbase: checked with the rear's peak
  CHECK_THROWS_WITH(SingleTrack(p), Catch::Contains("cg_height_m"));
  const SingleTrack model;
  float x[9];
  model.init_state(mppi::VehicleState{1, 2, 0.5f, 6.f, 0.2f, 0.1f, 0.05f}, x);
  CHECK(x[0] == 1.f);
  CHECK(x[st::kVy] == 0.2f);
  CHECK(x[st::kRoll] == 0.f);
  CHECK(x[SingleTrack::kOmegaFront] == Approx(6.0 / 0.0975));
  CHECK(x[SingleTrack::kOmegaRear] == Approx(6.0 / 0.0975));
}

TEST_CASE("Vehicle parameter YAML: the shipped file, strict keys, errors with file and line",
          "[physics][params]") {
  // The shipped uncalibrated variant restates the defaults (so the two cannot drift apart
  // silently); the default file holds the calibrated values (tests/sysid/test_plant_calibration.cpp).
  const auto path = mppi::test::data_path("config/autorally_single_track_uncalibrated.yaml");
  const SingleTrackParams loaded = mppi::load_single_track_params(path);
  const SingleTrackParams d;
  CHECK(loaded.mass_kg == d.mass_kg);
  CHECK(loaded.yaw_inertia_kgm2 == d.yaw_inertia_kgm2);
  CHECK(loaded.cg_to_front_axle_m == d.cg_to_front_axle_m);
  CHECK(loaded.cg_to_rear_axle_m == d.cg_to_rear_axle_m);
  CHECK(loaded.cg_height_m == d.cg_height_m);
  CHECK(loaded.wheel_radius_m == d.wheel_radius_m);
  CHECK(loaded.front_wheel_inertia_kgm2 == d.front_wheel_inertia_kgm2);
  CHECK(loaded.rear_wheel_inertia_kgm2 == d.rear_wheel_inertia_kgm2);
  CHECK(loaded.gravity_mps2 == d.gravity_mps2);
  CHECK(loaded.tyre.B == d.tyre.B);
  CHECK(loaded.tyre.C == d.tyre.C);
  CHECK(loaded.tyre.D == d.tyre.D);
  CHECK(loaded.tyre.E == d.tyre.E);
  CHECK(loaded.tyre.Sh == d.tyre.Sh);
  CHECK(loaded.tyre.Sv == d.tyre.Sv);
  CHECK(loaded.max_steer_rad == d.max_steer_rad);
  CHECK(loaded.stall_torque_Nm == d.stall_torque_Nm);
  CHECK(loaded.no_load_speed_mps == d.no_load_speed_mps);
  CHECK(loaded.brake_torque_ratio == d.brake_torque_ratio);
  CHECK(loaded.rolling_resistance == d.rolling_resistance);
  CHECK(loaded.rolling_resistance_speed_mps == d.rolling_resistance_speed_mps);
  CHECK(loaded.aero_drag_kgpm == d.aero_drag_kgpm);
  CHECK(loaded.slip_speed_floor_mps == d.slip_speed_floor_mps);
  CHECK(loaded.slip_blend == d.slip_blend);

  // Partial files keep defaults for the rest.
  const auto partial = mppi::single_track_params_from_yaml("mass_kg: 20.5\ntyre:\n  D: 0.9\n", "mem.yaml");
  CHECK(partial.mass_kg == 20.5);
  CHECK(partial.tyre.D == 0.9);
  CHECK(partial.tyre.B == d.tyre.B);
  CHECK(partial.yaw_inertia_kgm2 == d.yaw_inertia_kgm2);

  using Catch::Contains;
  CHECK_THROWS_WITH(mppi::single_track_params_from_yaml("mass_kg: 20\nmass: 3\n", "car.yaml"),
                    Contains("car.yaml:2") && Contains("unknown key 'mass'"));
  CHECK_THROWS_WITH(mppi::single_track_params_from_yaml("tyre:\n  B: 1\n  F: 2\n", "car.yaml"),
                    Contains("car.yaml:3") && Contains("unknown key 'F'"));
  CHECK_THROWS_WITH(mppi::single_track_params_from_yaml("cg_height_m: tall\n", "car.yaml"),
                    Contains("car.yaml:1") && Contains("cg_height_m") && Contains("tall"));
  CHECK_THROWS_WITH(mppi::single_track_params_from_yaml("mass_kg: -2\n", "car.yaml"),
                    Contains("car.yaml") && Contains("mass_kg"));
  CHECK_THROWS_WITH(mppi::single_track_params_from_yaml("mass_kg: [1, 2\n", "car.yaml"),
                    Contains("car.yaml") && Contains("YAML"));
  CHECK_THROWS_WITH(mppi::load_single_track_params("/nonexistent/car.yaml"), Contains("/nonexistent/car.yaml"));

  const auto kin = mppi::kinematic_bicycle_params_from_yaml("wheelbase_m: 0.6\nmax_accel_mps2: 3\n", "k.yaml");
  CHECK(kin.wheelbase_m == 0.6);
  CHECK(kin.max_accel_mps2 == 3.0);
  CHECK(kin.speed_damping_per_s == mppi::KinematicBicycleParams{}.speed_damping_per_s);
  CHECK_THROWS_WITH(mppi::kinematic_bicycle_params_from_yaml("wheel_base: 1\n", "k.yaml"),
                    Contains("k.yaml:1") && Contains("unknown key 'wheel_base'"));
}
