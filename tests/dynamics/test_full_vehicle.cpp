// The full vehicle model: rest equilibrium; free heave decay and roll frequency against the
// closed forms of the linear suspension; the suspension energy balance (stored spring energy,
// gravity, kinetic energy change only by the damper power); mirror symmetry; the stiff-
// suspension limit (-> the double-track); steady-cornering roll and pitch against the closed
// form; float batch vs double; YAML file.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <random>
#include <string>

#include "dynamics/double_track.hpp"
#include "dynamics/full_vehicle.hpp"
#include "dynamics/vehicle_params.hpp"
#include "error_of.hpp"
#include "mppi/concepts.hpp"
#include "test_data.hpp"

using mppi::DoubleTrack;
using mppi::FullVehicle;
using mppi::FullVehicleParams;
namespace st = mppi::state;

static_assert(mppi::VehicleDynamics<FullVehicle>);

namespace {

using State = std::array<double, FullVehicle::kNx>;

State rest_state() { return State{}; }

State random_state(std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-1, 1);
  State x{};
  x[st::kX] = 5 * U(rng);
  x[st::kY] = 5 * U(rng);
  x[st::kYaw] = 3 * U(rng);
  x[st::kVx] = 8 + 7 * U(rng);
  x[st::kVy] = 1.5 * U(rng);
  x[st::kYawRate] = 1.5 * U(rng);
  x[st::kRoll] = 0.05 * U(rng);
  const double R = FullVehicleParams{}.base.wheel_radius_m;
  for (int i = 0; i < 4; ++i) x[FullVehicle::kOmega + i] = x[st::kVx] / R * (1 + 0.3 * U(rng));
  x[FullVehicle::kPitch] = 0.03 * U(rng);
  x[FullVehicle::kHeave] = 0.01 * U(rng);
  x[FullVehicle::kRollRate] = 0.5 * U(rng);
  x[FullVehicle::kPitchRate] = 0.5 * U(rng);
  x[FullVehicle::kHeaveRate] = 0.1 * U(rng);
  return x;
}

State mirror(const State& x) {
  State m = x;
  for (int i : {st::kY, st::kYaw, st::kVy, st::kYawRate, st::kRoll, FullVehicle::kRollRate}) m[i] = -x[i];
  std::swap(m[FullVehicle::kOmega], m[FullVehicle::kOmega + 1]);
  std::swap(m[FullVehicle::kOmega + 2], m[FullVehicle::kOmega + 3]);
  return m;
}

// Linear roll and pitch stiffness of the four corners (N m / rad).
double roll_stiffness(const FullVehicleParams& p) {
  return 0.5 * (p.front_spring_Npm * p.front_track_m * p.front_track_m +
                p.rear_spring_Npm * p.rear_track_m * p.rear_track_m);
}

void simulate(const mppi::FullVehicleCoeffs<double>& k, State& x, const double* u, double dt, int steps) {
  for (int n = 0; n < steps; ++n) FullVehicle::step_double(k, x.data(), u, dt);
}

}  // namespace

TEST_CASE("Full vehicle at rest is in equilibrium with the static loads", "[physics][full_vehicle]") {
  const FullVehicleParams p;
  const FullVehicle fv(p);
  const State x = rest_state();
  const double u[2] = {0.3, 0.0};
  State dx{};
  fv.derivatives(x.data(), u, dx.data());
  for (int i = 0; i < FullVehicle::kNx; ++i) CHECK(dx[i] == Approx(0).margin(1e-12));
  const auto f = fv.forces(x.data(), u);
  const double mg = p.base.mass_kg * p.base.gravity_mps2, L = p.base.wheelbase_m();
  CHECK(f.planar.fz_N[0] + f.planar.fz_N[1] == Approx(mg * p.base.cg_to_rear_axle_m / L));
  CHECK(f.planar.fz_N[2] + f.planar.fz_N[3] == Approx(mg * p.base.cg_to_front_axle_m / L));
  CHECK(p.sprung_mass_kg() == Approx(21.88 - 2 * (0.82 + 0.89)));
}

TEST_CASE("Full vehicle free heave decays like the closed-form damped oscillator",
          "[physics][full_vehicle]") {
  // With l_f K_f = l_r K_r and l_f C_f = l_r C_r heave does not couple into pitch:
  // z'' + 2 (C_f + C_r) / m^s z' + 2 (K_f + K_r) / m^s z = 0.
  FullVehicleParams p;
  p.rear_spring_Npm = p.front_spring_Npm * p.base.cg_to_front_axle_m / p.base.cg_to_rear_axle_m;
  p.rear_damper_Nspm = p.front_damper_Nspm * p.base.cg_to_front_axle_m / p.base.cg_to_rear_axle_m;
  const auto k = mppi::full_vehicle_coeffs(p);
  const double ms = p.sprung_mass_kg();
  const double wn = std::sqrt(2 * (p.front_spring_Npm + p.rear_spring_Npm) / ms);
  const double zeta = (p.front_damper_Nspm + p.rear_damper_Nspm) / (ms * wn);
  REQUIRE(zeta < 1);
  const double wd = wn * std::sqrt(1 - zeta * zeta), z0 = 0.01;
  State x = rest_state();
  x[FullVehicle::kHeave] = z0;
  const double u[2] = {0.0, 0.0};
  const double dt = 1e-5;
  double max_err = 0, max_pitch = 0;
  for (int n = 1; n <= 50000; ++n) {  // 0.5 s
    FullVehicle::step_double(k, x.data(), u, dt);
    const double t = n * dt;
    const double z = z0 * std::exp(-zeta * wn * t) * (std::cos(wd * t) + zeta * wn / wd * std::sin(wd * t));
    max_err = std::max(max_err, std::abs(x[FullVehicle::kHeave] - z));
    max_pitch = std::max(max_pitch, std::abs(x[FullVehicle::kPitch]));
  }
  CHECK(max_err < 0.005 * z0);
  CHECK(max_pitch < 1e-12);
}

TEST_CASE("Full vehicle free roll oscillates at sqrt((K_roll - m^s g (h^s - h^c)) / I^R_x)",
          "[physics][full_vehicle]") {
  FullVehicleParams p;
  p.front_damper_Nspm = p.rear_damper_Nspm = 0.0;
  const auto k = mppi::full_vehicle_coeffs(p);
  const double ms = p.sprung_mass_kg(), g = p.base.gravity_mps2;
  const double w = std::sqrt((roll_stiffness(p) - ms * g * (p.sprung_cg_height_m - p.roll_centre_height_m)) /
                             p.roll_inertia_kgm2);
  State x = rest_state();
  x[st::kRoll] = 0.02;
  const double u[2] = {0.0, 0.0};
  const double dt = 1e-5;
  // Time of the 10th downward zero crossing of the roll angle = 9.75 periods.
  int crossings = 0;
  double prev = x[st::kRoll], t_cross = 0;
  for (int n = 1; n <= 400000 && crossings < 10; ++n) {
    FullVehicle::step_double(k, x.data(), u, dt);
    const double cur = x[st::kRoll];
    if (prev > 0 && cur <= 0) {
      ++crossings;
      t_cross = (n - 1 + prev / (prev - cur)) * dt;
    }
    prev = cur;
  }
  REQUIRE(crossings == 10);
  const double period = t_cross / 9.25;  // first downward crossing at T/4, then every T
  CHECK(period == Approx(2 * M_PI / w).epsilon(2e-3));
}

TEST_CASE("Full vehicle suspension energy changes only by the damper power", "[physics][full_vehicle]") {
  // Car still (no tyre forces): E = kinetic (heave, roll, pitch) + springs - the gravity
  // destabilisation of the small-angle model; dE/dt = -sum C_i (d dz_i / dt)^2.
  const FullVehicleParams p;
  const FullVehicle fv(p);
  const double ms = p.sprung_mass_kg(), g = p.base.gravity_mps2;
  const double hs = p.sprung_cg_height_m, hc = p.roll_centre_height_m;
  const double lf = p.base.cg_to_front_axle_m, lr = p.base.cg_to_rear_axle_m;
  const double xs[4] = {lf, lf, -lr, -lr};
  const double ys[4] = {p.front_track_m / 2, -p.front_track_m / 2, p.rear_track_m / 2, -p.rear_track_m / 2};
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int n = 0; n < 200; ++n) {
    State x = rest_state();
    x[st::kRoll] = 0.05 * U(rng);
    x[FullVehicle::kPitch] = 0.03 * U(rng);
    x[FullVehicle::kHeave] = 0.01 * U(rng);
    x[FullVehicle::kRollRate] = 0.5 * U(rng);
    x[FullVehicle::kPitchRate] = 0.5 * U(rng);
    x[FullVehicle::kHeaveRate] = 0.1 * U(rng);
    const double u[2] = {U(rng), 0.0};
    State dx{};
    fv.derivatives(x.data(), u, dx.data());
    const double z = x[FullVehicle::kHeave], th = x[FullVehicle::kPitch], ph = x[st::kRoll];
    const double vz = x[FullVehicle::kHeaveRate], dth = x[FullVehicle::kPitchRate], dph = x[FullVehicle::kRollRate];
    // dE/dt from the chain rule.
    double de = ms * vz * dx[FullVehicle::kHeaveRate] + p.pitch_inertia_kgm2 * dth * dx[FullVehicle::kPitchRate] +
                p.roll_inertia_kgm2 * dph * dx[FullVehicle::kRollRate];
    double damper_power = 0;
    for (int i = 0; i < 4; ++i) {
      const double kk = i < 2 ? p.front_spring_Npm : p.rear_spring_Npm;
      const double cc = i < 2 ? p.front_damper_Nspm : p.rear_damper_Nspm;
      const double dz = z - xs[i] * th + ys[i] * ph, ddz = vz - xs[i] * dth + ys[i] * dph;
      de += kk * dz * ddz;
      damper_power -= cc * ddz * ddz;
    }
    de -= ms * g * hs * th * dth + ms * g * (hs - hc) * ph * dph;
    CHECK(de == Approx(damper_power).margin(1e-10));
    CHECK(de <= 1e-12);
  }
}

TEST_CASE("Full vehicle is mirror symmetric", "[physics][full_vehicle]") {
  const FullVehicle fv{FullVehicleParams{}};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int n = 0; n < 200; ++n) {
    const State x = random_state(rng);
    const double u[2] = {U(rng), U(rng)}, um[2] = {-u[0], u[1]};
    State dx{}, dxm{};
    fv.derivatives(x.data(), u, dx.data());
    fv.derivatives(mirror(x).data(), um, dxm.data());
    const State back = mirror(dxm);
    for (int i = 0; i < FullVehicle::kNx; ++i) CHECK(back[i] == Approx(dx[i]).margin(1e-9));
  }
}

TEST_CASE("Full vehicle with a stiff suspension tends to the double-track", "[physics][full_vehicle]") {
  // Same manoeuvre (sine steer, throttle steps) from 5 m/s; stiffness x400, damping x20
  // (same damping ratio). Deviation from the double-track shrinks with stiffness.
  auto run = [](double stiff_factor) {
    FullVehicleParams p;
    p.front_spring_Npm *= stiff_factor;
    p.rear_spring_Npm *= stiff_factor;
    p.front_damper_Nspm *= std::sqrt(stiff_factor);
    p.rear_damper_Nspm *= std::sqrt(stiff_factor);
    const auto kf = mppi::full_vehicle_coeffs(p);
    const DoubleTrack dt(p.rigid_limit());
    State x = rest_state();
    std::array<double, DoubleTrack::kNx> xd{};
    x[st::kVx] = xd[st::kVx] = 5.0;
    for (int i = 0; i < 4; ++i) x[FullVehicle::kOmega + i] = xd[DoubleTrack::kOmega + i] = 5.0 / p.base.wheel_radius_m;
    const double h = 1e-4;
    double max_dev = 0;
    for (int n = 0; n < 30000; ++n) {  // 3 s
      const double t = n * h;
      const double u[2] = {0.6 * std::sin(2.0 * t), t < 1.5 ? 0.8 : -0.3};
      FullVehicle::step_double(kf, x.data(), u, h);
      std::array<double, DoubleTrack::kNx> dxd{};
      dt.derivatives(xd.data(), u, dxd.data());
      for (int i = 0; i < DoubleTrack::kNx; ++i) xd[i] += h * dxd[i];
      for (int i : {st::kVx, st::kVy, st::kYawRate})
        max_dev = std::max(max_dev, std::abs(x[i] - xd[i]));
    }
    return max_dev;
  };
  const double dev_default = run(1.0), dev_stiff = run(400.0);
  INFO("max |dv|, |dr| default " << dev_default << ", stiff " << dev_stiff);
  CHECK(dev_stiff < 0.01);
  CHECK(dev_stiff < 0.25 * dev_default);
}

TEST_CASE("Full vehicle steady cornering: roll and pitch match the closed form", "[physics][full_vehicle]") {
  const FullVehicleParams p;
  const FullVehicle fv(p);
  const auto k = mppi::full_vehicle_coeffs(p);
  State x = rest_state();
  x[st::kVx] = 3.0;
  for (int i = 0; i < 4; ++i) x[FullVehicle::kOmega + i] = 3.0 / p.base.wheel_radius_m;
  const double u[2] = {0.5, 0.35};
  simulate(k, x, u, 1e-3, 30000);  // 30 s
  State dx{};
  fv.derivatives(x.data(), u, dx.data());
  REQUIRE(std::abs(dx[st::kVx]) < 1e-3);
  REQUIRE(std::abs(dx[st::kYawRate]) < 1e-3);
  const auto f = fv.forces(x.data(), u);
  REQUIRE(f.ay_mps2 > 2.0);
  const double ms = p.sprung_mass_kg(), g = p.base.gravity_mps2;
  const double hs = p.sprung_cg_height_m, hc = p.roll_centre_height_m;
  // Roll: K_roll phi = m^s (h^s - h^c) (a_y + g phi).
  const double roll = ms * (hs - hc) * f.ay_mps2 / (roll_stiffness(p) - ms * g * (hs - hc));
  CHECK(x[st::kRoll] == Approx(roll).epsilon(1e-3));
  CHECK(x[st::kRoll] > 0.01);  // right side down in a left turn
  // Heave and pitch: 2x2 linear statics of the corners.
  const double Kf = p.front_spring_Npm, Kr = p.rear_spring_Npm;
  const double lf = p.base.cg_to_front_axle_m, lr = p.base.cg_to_rear_axle_m;
  Eigen::Matrix2d A;
  A << 2 * (Kf + Kr), -2 * (Kf * lf - Kr * lr), -2 * (Kf * lf - Kr * lr),
      2 * (Kf * lf * lf + Kr * lr * lr) - ms * g * hs;
  const Eigen::Vector2d b(0.0, -ms * hs * f.planar.body_fx_N / p.base.mass_kg);
  const Eigen::Vector2d zt = A.partialPivLu().solve(b);
  CHECK(x[FullVehicle::kHeave] == Approx(zt(0)).margin(1e-6));
  CHECK(x[FullVehicle::kPitch] == Approx(zt(1)).margin(1e-6));
  // Cornering: lateral load moves to the outer (right) wheels.
  CHECK(f.planar.fz_N[1] > f.planar.fz_N[0]);
  CHECK(f.planar.fz_N[3] > f.planar.fz_N[2]);
}

TEST_CASE("Full vehicle batched float step<64> equals the double step", "[physics][full_vehicle]") {
  const FullVehicle fv{FullVehicleParams{}};
  const auto k = mppi::full_vehicle_coeffs(FullVehicleParams{});
  constexpr int W = mppi::kChunk;
  constexpr int N = FullVehicle::kNx;
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> U(-1, 1);
  std::array<float, N * W> xb{};
  std::array<float, 2 * W> ub{};
  std::array<State, W> xs{};
  std::array<std::array<double, 2>, W> us{};
  for (int j = 0; j < W; ++j) {
    xs[j] = random_state(rng);
    us[j] = {U(rng), U(rng)};
    for (int i = 0; i < N; ++i) xb[i * W + j] = static_cast<float>(xs[j][i]);
    for (int i = 0; i < 2; ++i) ub[i * W + j] = static_cast<float>(us[j][i]);
  }
  fv.step<W>(mppi::Batch<N, W>{xb.data()}, mppi::ConstBatch<2, W>{ub.data()}, 0.02f, nullptr);
  for (int j = 0; j < W; ++j) {
    State expect = xs[j];
    FullVehicle::step_double(k, expect.data(), us[j].data(), 0.02);
    for (int i = 0; i < N; ++i)
      CHECK(xb[i * W + j] == Approx(expect[i]).margin(2e-3 * std::max(1.0, std::abs(expect[i]))));
  }
}

TEST_CASE("Full vehicle at the controller's 0.02 s stays finite and bounded", "[physics][full_vehicle]") {
  // Random controls held for 0.1 s, 2000 steps per lane, from random states.
  const FullVehicle fv{FullVehicleParams{}};
  constexpr int W = mppi::kChunk;
  constexpr int N = FullVehicle::kNx;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-1, 1);
  std::array<float, N * W> xb{};
  std::array<float, 2 * W> ub{};
  for (int j = 0; j < W; ++j) {
    const State s = random_state(rng);
    for (int i = 0; i < N; ++i) xb[i * W + j] = static_cast<float>(s[i]);
  }
  bool ok = true;
  for (int n = 0; n < 2000; ++n) {
    if (n % 5 == 0)
      for (auto& v : ub) v = static_cast<float>(U(rng));
    fv.step<W>(mppi::Batch<N, W>{xb.data()}, mppi::ConstBatch<2, W>{ub.data()}, 0.02f, nullptr);
    for (int j = 0; j < W; ++j) {
      ok &= std::isfinite(xb[st::kVx * W + j]) && std::abs(xb[st::kVx * W + j]) < 40;
      ok &= std::abs(xb[st::kRoll * W + j]) < 0.3 && std::abs(xb[FullVehicle::kPitch * W + j]) < 0.3;
      ok &= std::abs(xb[FullVehicle::kHeave * W + j]) < 0.1;
    }
  }
  CHECK(ok);
}

TEST_CASE("Full-vehicle parameters: YAML file, round trip, errors", "[physics][full_vehicle]") {
  const FullVehicleParams file =
      mppi::load_full_vehicle_params(mppi::test::data_path("config/autorally_full_vehicle_uncalibrated.yaml"));
  const FullVehicleParams def;
  CHECK(file.base.mass_kg == 21.88);
  CHECK(file.front_spring_Npm == 2000.0);
  CHECK(file.roll_inertia_kgm2 == def.roll_inertia_kgm2);
  CHECK(file.pitch_inertia_kgm2 == def.pitch_inertia_kgm2);
  CHECK(file.base.aero_drag_kgpm == 0.0);
  // The chosen inertias are the bifilar ones moved by the parallel-axis theorem.
  const double ms = def.sprung_mass_kg();
  CHECK(def.roll_inertia_kgm2 ==
        Approx(0.347 + ms * std::pow(def.sprung_cg_height_m - def.roll_centre_height_m, 2)).epsilon(2e-3));
  CHECK(def.pitch_inertia_kgm2 == Approx(1.131 + ms * std::pow(def.sprung_cg_height_m, 2)).epsilon(1e-3));
  // 0.5 rho C_D A equals the single-track's drag constant.
  CHECK(0.5 * def.air_density_kgpm3 * def.drag_coefficient * def.frontal_area_m2 ==
        Approx(mppi::SingleTrackParams{}.aero_drag_kgpm).epsilon(0.01));

  FullVehicleParams changed;
  changed.front_damper_Nspm = 77.0;
  changed.base.yaw_inertia_kgm2 = 1.0;
  const FullVehicleParams back = mppi::full_vehicle_params_from_yaml(mppi::to_yaml(changed), "round");
  CHECK(back.front_damper_Nspm == 77.0);
  CHECK(back.base.yaw_inertia_kgm2 == 1.0);

  // Named access covers every YAML key and points into the struct.
  FullVehicleParams named;
  int found = 0;
  for (const auto& np : mppi::named_parameters(named)) {
    if (np.key == "front_spring_Npm") *np.value = 1234.0, ++found;
    if (np.key == "tyre.Sv") *np.value = 0.2, ++found;
    CHECK(np.key != "aero_drag_kgpm");
  }
  CHECK(found == 2);
  CHECK(named.front_spring_Npm == 1234.0);
  CHECK(named.base.tyre.Sv == 0.2);
  // single-track core (with brake_torque_ratio and the three rear-tyre scales), chassis, corners
  CHECK(mppi::named_parameters(named).size() == 20 + 15 + 6);

  using mppi::test::error_of;
  CHECK_THAT(error_of([] { mppi::full_vehicle_params_from_yaml("aero_drag_kgpm: 0.05\n", "fv.yaml"); }),
             Catch::Contains("fv.yaml:1") && Catch::Contains("aero_drag_kgpm"));
  CHECK_THAT(error_of([] { mppi::full_vehicle_params_from_yaml("front_spring_Npm: 10\nrear_spring_Npm: 10\n", "fv.yaml"); }),
             Catch::Contains("fv.yaml") && Catch::Contains("roll stiffness"));
  CHECK_THAT(error_of([] { mppi::full_vehicle_params_from_yaml("front_wheel_mass_kg: 20\n", "fv.yaml"); }),
             Catch::Contains("sprung mass"));
}
