// The double-track model: limits against the single-track (zero load transfer and zero track
// width; straight-line driving), the quasi-static moment balances of the normal loads, the
// power balance (kinetic energy changes by exactly the tyre, motor and resistance power, and
// never grows without throttle), mirror symmetry, float batch vs double, and its YAML file.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <string>

#include "dynamics/double_track.hpp"
#include "dynamics/single_track.hpp"
#include "dynamics/vehicle_params.hpp"
#include "error_of.hpp"
#include "mppi/concepts.hpp"
#include "test_data.hpp"

using mppi::DoubleTrack;
using mppi::DoubleTrackParams;
using mppi::SingleTrack;
namespace st = mppi::state;

static_assert(mppi::VehicleDynamics<DoubleTrack>);

namespace {

using State = std::array<double, DoubleTrack::kNx>;

// A random driving state: speeds 1..15 m/s, sliding, wheels spinning or locking.
State random_state(std::mt19937& rng, bool equal_sides = false) {
  std::uniform_real_distribution<double> U(-1, 1);
  State x{};
  x[st::kX] = 5 * U(rng);
  x[st::kY] = 5 * U(rng);
  x[st::kYaw] = 3 * U(rng);
  x[st::kVx] = 8 + 7 * U(rng);
  x[st::kVy] = 1.5 * U(rng);
  x[st::kYawRate] = 1.5 * U(rng);
  const double R = DoubleTrackParams{}.base.wheel_radius_m;
  for (int i = 0; i < 4; ++i) x[DoubleTrack::kOmega + i] = x[st::kVx] / R * (1 + 0.3 * U(rng));
  if (equal_sides) {
    x[DoubleTrack::kOmega + 1] = x[DoubleTrack::kOmega];
    x[DoubleTrack::kOmega + 3] = x[DoubleTrack::kOmega + 2];
  }
  return x;
}

double rel_diff(double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); }

// Kinetic energy: body translation and yaw, four spinning wheels.
double kinetic_energy(const DoubleTrackParams& p, const State& x) {
  const double m = p.base.mass_kg;
  double e = 0.5 * m * (x[st::kVx] * x[st::kVx] + x[st::kVy] * x[st::kVy]) +
             0.5 * p.base.yaw_inertia_kgm2 * x[st::kYawRate] * x[st::kYawRate];
  for (int i = 0; i < 4; ++i) {
    const double iw = (i < 2 ? p.base.front_wheel_inertia_kgm2 : p.base.rear_wheel_inertia_kgm2) / 2;
    e += 0.5 * iw * x[DoubleTrack::kOmega + i] * x[DoubleTrack::kOmega + i];
  }
  return e;
}

// Mirror image in the x-z plane: y, yaw, vy, yaw rate, steer change sign; left <-> right.
State mirror(const State& x) {
  State m = x;
  m[st::kY] = -x[st::kY];
  m[st::kYaw] = -x[st::kYaw];
  m[st::kVy] = -x[st::kVy];
  m[st::kYawRate] = -x[st::kYawRate];
  std::swap(m[DoubleTrack::kOmega], m[DoubleTrack::kOmega + 1]);
  std::swap(m[DoubleTrack::kOmega + 2], m[DoubleTrack::kOmega + 3]);
  return m;
}

}  // namespace

TEST_CASE("Double-track without load transfer and track width is the single-track",
          "[physics][double_track]") {
  DoubleTrackParams p;
  p.front_track_m = p.rear_track_m = 1e-9;
  p.lateral_load_transfer = 0.0;
  const DoubleTrack dt(p);
  const SingleTrack single(p.base);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int n = 0; n < 300; ++n) {
    const State x = random_state(rng, true);
    const double u[2] = {U(rng), U(rng)};
    double xs[SingleTrack::kNx];
    std::copy(x.begin(), x.begin() + st::kCommonStates, xs);
    xs[SingleTrack::kOmegaFront] = x[DoubleTrack::kOmega];
    xs[SingleTrack::kOmegaRear] = x[DoubleTrack::kOmega + 2];
    State dx{};
    double dxs[SingleTrack::kNx];
    dt.derivatives(x.data(), u, dx.data());
    single.derivatives(xs, u, dxs);
    for (int i = 0; i < st::kCommonStates; ++i) CHECK(rel_diff(dx[i], dxs[i]) < 1e-7);
    CHECK(rel_diff(dx[DoubleTrack::kOmega], dxs[SingleTrack::kOmegaFront]) < 1e-7);
    CHECK(rel_diff(dx[DoubleTrack::kOmega + 1], dxs[SingleTrack::kOmegaFront]) < 1e-7);
    CHECK(rel_diff(dx[DoubleTrack::kOmega + 2], dxs[SingleTrack::kOmegaRear]) < 1e-7);
    CHECK(rel_diff(dx[DoubleTrack::kOmega + 3], dxs[SingleTrack::kOmegaRear]) < 1e-7);
  }
}

TEST_CASE("Double-track in a straight line is the single-track (AutoRally values, full transfer)",
          "[physics][double_track]") {
  const DoubleTrack dt{DoubleTrackParams{}};
  const SingleTrack single(DoubleTrackParams{}.base);
  for (double vx : {0.5, 3.0, 9.0}) {
    for (double throttle : {-1.0, 0.0, 0.4, 1.0}) {
      State x{};
      x[st::kVx] = vx;
      const double R = DoubleTrackParams{}.base.wheel_radius_m;
      const double wf = vx / R * 0.97, wr = vx / R * 1.2;
      x[DoubleTrack::kOmega] = x[DoubleTrack::kOmega + 1] = wf;
      x[DoubleTrack::kOmega + 2] = x[DoubleTrack::kOmega + 3] = wr;
      double xs[SingleTrack::kNx] = {0, 0, 0, vx, 0, 0, 0, wf, wr};
      const double u[2] = {0.0, throttle};
      State dx{};
      double dxs[SingleTrack::kNx];
      dt.derivatives(x.data(), u, dx.data());
      single.derivatives(xs, u, dxs);
      CHECK(rel_diff(dx[st::kVx], dxs[st::kVx]) < 1e-12);
      CHECK(dx[st::kVy] == Approx(0).margin(1e-12));
      CHECK(dx[st::kYawRate] == Approx(0).margin(1e-12));
      CHECK(rel_diff(dx[DoubleTrack::kOmega + 2], dxs[SingleTrack::kOmegaRear]) < 1e-12);
      CHECK(rel_diff(dx[DoubleTrack::kOmega], dxs[SingleTrack::kOmegaFront]) < 1e-12);
    }
  }
}

TEST_CASE("Double-track normal loads satisfy the quasi-static force and moment balances",
          "[physics][double_track]") {
  const DoubleTrackParams p;
  const DoubleTrack dt(p);
  const double m = p.base.mass_kg, g = p.base.gravity_mps2, h = p.base.cg_height_m;
  const double lf = p.base.cg_to_front_axle_m, lr = p.base.cg_to_rear_axle_m;
  const double wf = p.front_track_m, wr = p.rear_track_m, chi = p.front_roll_share;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> U(-1, 1);
  int checked = 0;
  for (int n = 0; n < 300; ++n) {
    const State x = random_state(rng);
    const double u[2] = {U(rng), U(rng)};
    const auto f = dt.forces(x.data(), u);
    bool lifted = false;
    for (double fz : f.fz_N) lifted |= fz <= 0;
    if (lifted) continue;  // clamped: the balance does not hold by design
    ++checked;
    const double fz_sum = f.fz_N[0] + f.fz_N[1] + f.fz_N[2] + f.fz_N[3];
    CHECK(fz_sum == Approx(m * g).epsilon(1e-12));
    // Pitch about the CG: normal loads balance the tyre forces acting h below it.
    const double pitch = (f.fz_N[0] + f.fz_N[1]) * lf - (f.fz_N[2] + f.fz_N[3]) * lr;
    CHECK(pitch == Approx(-h * f.body_fx_N).margin(1e-9));
    // Roll, per axle: the axle carries its share of h Fy.
    const double roll_front = (f.fz_N[0] - f.fz_N[1]) * wf / 2;
    const double roll_rear = (f.fz_N[2] - f.fz_N[3]) * wr / 2;
    CHECK(roll_front == Approx(-chi * h * f.body_fy_N).margin(1e-9));
    CHECK(roll_rear == Approx(-(1 - chi) * h * f.body_fy_N).margin(1e-9));
    // The forces are the friction coefficients times these loads (self-consistent solve).
    double fy = 0;
    const double sd = std::sin(f.delta_rad), cd = std::cos(f.delta_rad);
    for (int i = 0; i < 4; ++i) {
      const double mx = f.tyre[i].mu_x, my = f.tyre[i].mu_y;
      fy += (i < 2 ? mx * sd + my * cd : my) * f.fz_N[i];
    }
    CHECK(fy == Approx(f.body_fy_N).margin(1e-9));
  }
  CHECK(checked > 200);
}

TEST_CASE("Double-track power balance: kinetic energy changes by the dissipated power",
          "[physics][double_track]") {
  const DoubleTrackParams p;
  const DoubleTrack dt(p);
  const double R = p.base.wheel_radius_m;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int n = 0; n < 300; ++n) {
    const State x = random_state(rng);
    const double throttle = n % 2 ? 0.0 : U(rng);
    const double u[2] = {U(rng), throttle};
    State dx{};
    dt.derivatives(x.data(), u, dx.data());
    // dE/dt by the chain rule on the model's derivatives.
    double de = p.base.mass_kg * (x[st::kVx] * dx[st::kVx] + x[st::kVy] * dx[st::kVy]) +
                p.base.yaw_inertia_kgm2 * x[st::kYawRate] * dx[st::kYawRate];
    for (int i = 0; i < 4; ++i)
      de += (i < 2 ? p.base.front_wheel_inertia_kgm2 : p.base.rear_wheel_inertia_kgm2) / 2 *
            x[DoubleTrack::kOmega + i] * dx[DoubleTrack::kOmega + i];
    // The power of every force, from the diagnostics: tyre friction times contact sliding
    // velocity, motor torque times carrier speed, resistance times speed.
    const auto f = dt.forces(x.data(), u);
    double power = f.resist_force_N * x[st::kVx];
    for (int i = 0; i < 4; ++i)
      power += f.fx_N[i] * (f.wheel_vx_mps[i] - x[DoubleTrack::kOmega + i] * R) +
               f.fy_N[i] * f.wheel_vy_mps[i];
    power += f.drive_torque_Nm * 0.5 * (x[DoubleTrack::kOmega + 2] + x[DoubleTrack::kOmega + 3]);
    CHECK(de == Approx(power).margin(1e-9 * std::max(1.0, kinetic_energy(p, x))));
    if (throttle == 0.0) CHECK(de <= 1e-9);
  }
}

TEST_CASE("Double-track is mirror symmetric", "[physics][double_track]") {
  const DoubleTrack dt{DoubleTrackParams{}};
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int n = 0; n < 200; ++n) {
    const State x = random_state(rng);
    const double u[2] = {U(rng), U(rng)}, um[2] = {-u[0], u[1]};
    State dx{}, dxm{};
    dt.derivatives(x.data(), u, dx.data());
    dt.derivatives(mirror(x).data(), um, dxm.data());
    const State back = mirror(dxm);
    for (int i = 0; i < DoubleTrack::kNx; ++i) CHECK(back[i] == Approx(dx[i]).margin(1e-9));
  }
}

TEST_CASE("Double-track steady cornering: the outer wheels carry the load transfer m a_y h / w",
          "[physics][double_track]") {
  // Constant steer and throttle until steady; then a_y = Vx r and the closed-form transfer.
  const DoubleTrackParams p;
  const DoubleTrack dt(p);
  State x{};
  x[st::kVx] = 3.0;
  for (int i = 0; i < 4; ++i) x[DoubleTrack::kOmega + i] = 3.0 / p.base.wheel_radius_m;
  const double u[2] = {0.5, 0.35};
  const double h_step = 1e-3;
  for (int n = 0; n < 30000; ++n) {  // 30 s, RK2 (Heun) in double
    State k1{}, k2{}, x2 = x;
    dt.derivatives(x.data(), u, k1.data());
    for (int i = 0; i < DoubleTrack::kNx; ++i) x2[i] += h_step * k1[i];
    dt.derivatives(x2.data(), u, k2.data());
    for (int i = 0; i < DoubleTrack::kNx; ++i) x[i] += 0.5 * h_step * (k1[i] + k2[i]);
  }
  State dx{};
  dt.derivatives(x.data(), u, dx.data());
  REQUIRE(std::abs(dx[st::kVx]) < 1e-3);
  REQUIRE(std::abs(dx[st::kYawRate]) < 1e-3);
  const double ay = x[st::kVx] * x[st::kYawRate];  // centripetal, steady state
  REQUIRE(ay > 2.0);                               // a real corner
  const auto f = dt.forces(x.data(), u);
  const double m = p.base.mass_kg, h = p.base.cg_height_m;
  // Outer (right, turning left) minus inner: 2 chi m a_y h / w per axle.
  CHECK(f.fz_N[1] - f.fz_N[0] ==
        Approx(2 * p.front_roll_share * m * ay * h / p.front_track_m).epsilon(2e-3));
  CHECK(f.fz_N[3] - f.fz_N[2] ==
        Approx(2 * (1 - p.front_roll_share) * m * ay * h / p.rear_track_m).epsilon(2e-3));
}

TEST_CASE("Double-track batched float step<64> equals Euler in double", "[physics][double_track]") {
  const DoubleTrack dt{DoubleTrackParams{}};
  constexpr int W = mppi::kChunk;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  std::array<float, DoubleTrack::kNx * W> xb{};
  std::array<float, 2 * W> ub{};
  std::array<State, W> xs{};
  std::array<std::array<double, 2>, W> us{};
  for (int j = 0; j < W; ++j) {
    xs[j] = random_state(rng);
    us[j] = {U(rng), U(rng)};
    for (int i = 0; i < DoubleTrack::kNx; ++i) xb[i * W + j] = static_cast<float>(xs[j][i]);
    for (int i = 0; i < 2; ++i) ub[i * W + j] = static_cast<float>(us[j][i]);
  }
  const float step = 0.02f;
  dt.step<W>(mppi::Batch<DoubleTrack::kNx, W>{xb.data()}, mppi::ConstBatch<2, W>{ub.data()}, step,
             nullptr);
  for (int j = 0; j < W; ++j) {
    State dx{};
    dt.derivatives(xs[j].data(), us[j].data(), dx.data());
    for (int i = 0; i < DoubleTrack::kNx; ++i) {
      const double expect = xs[j][i] + step * dx[i];
      CHECK(xb[i * W + j] == Approx(expect).margin(2e-3 * std::max(1.0, std::abs(expect))));
    }
  }
}

TEST_CASE("Double-track parameters: YAML file, round trip, errors", "[physics][double_track]") {
  const DoubleTrackParams file =
      mppi::load_double_track_params(mppi::test::data_path("config/autorally_double_track_uncalibrated.yaml"));
  const DoubleTrackParams def;
  CHECK(file.base.mass_kg == def.base.mass_kg);
  CHECK(file.front_track_m == 0.395);
  CHECK(file.rear_track_m == 0.405);
  CHECK(file.front_roll_share == def.front_roll_share);
  CHECK(file.base.tyre.E == def.base.tyre.E);
  CHECK(file.base.aero_drag_kgpm == def.base.aero_drag_kgpm);
  // front_roll_share is the roll-stiffness share for K_f = K_r.
  CHECK(def.front_roll_share == Approx(0.395 * 0.395 / (0.395 * 0.395 + 0.405 * 0.405)).epsilon(1e-6));

  DoubleTrackParams changed;
  changed.front_track_m = 0.5;
  changed.base.tyre.B = 2.0;
  const DoubleTrackParams back = mppi::double_track_params_from_yaml(mppi::to_yaml(changed), "round");
  CHECK(back.front_track_m == 0.5);
  CHECK(back.base.tyre.B == 2.0);

  using mppi::test::error_of;
  const std::string unknown =
      error_of([] { mppi::double_track_params_from_yaml("mass_kg: 20\nfront_trak_m: 0.4\n", "dt.yaml"); });
  CHECK_THAT(unknown, Catch::Contains("dt.yaml:2") && Catch::Contains("front_trak_m"));
  const std::string bad = error_of([] { mppi::double_track_params_from_yaml("rear_track_m: -1\n", "dt.yaml"); });
  CHECK_THAT(bad, Catch::Contains("dt.yaml") && Catch::Contains("rear_track_m"));
  CHECK_THAT(error_of([] { DoubleTrackParams q; q.lateral_load_transfer = 2; DoubleTrack{q}; }),
             Catch::Contains("lateral_load_transfer"));
}

TEST_CASE("Double-track at the controller's 0.02 s stays finite and bounded", "[physics][double_track]") {
  // Random controls held for 0.1 s, 2000 steps per lane, from random sliding states.
  const DoubleTrack dt{DoubleTrackParams{}};
  constexpr int W = mppi::kChunk;
  constexpr int N = DoubleTrack::kNx;
  std::mt19937 rng(6);
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
    dt.step<W>(mppi::Batch<N, W>{xb.data()}, mppi::ConstBatch<2, W>{ub.data()}, 0.02f, nullptr);
    for (int j = 0; j < W; ++j) {
      ok &= std::isfinite(xb[st::kVx * W + j]) && std::abs(xb[st::kVx * W + j]) < 40;
      ok &= std::abs(xb[st::kYawRate * W + j]) < 20;
      for (int i = 0; i < 4; ++i) ok &= std::abs(xb[(DoubleTrack::kOmega + i) * W + j]) < 500;
    }
  }
  CHECK(ok);
}
