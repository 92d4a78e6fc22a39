// The independent evidence generator (evidence/) against closed forms: a pure delay shifts
// the response exactly, a servo rate limit bounds the steering slope, drag along the velocity
// vector follows the v^2 law, a grade adds g sin(theta), the battery's torque solves its own
// voltage equation; recordings are reproducible by seed; and the generator's sources include
// nothing of the diagnosis it is evidence for.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <fstream>
#include <random>
#include <sstream>

#include "base/error.hpp"
#include "sysid/prepared_recording.hpp"
#include "diagnose/model_family.hpp"
#include "diagnose/replay.hpp"
#include "dynamics/vehicle_params.hpp"
#include "evidence/actuators.hpp"
#include "evidence/car_physics.hpp"
#include "evidence/generator.hpp"
#include "sim/data_dir.hpp"
#include "sim/recording.hpp"
#include "test_data.hpp"

using namespace mppi;
using namespace mppi::evidence;

namespace {

CarConstants frictionless_straight() {
  CarConstants c;
  c.rolling_coefficient = 0;
  c.aero_drag_kgpm = 0;
  return c;
}

CarState rolling(double vx, const CarConstants& c) {
  CarState s{};
  s[kVx] = vx;
  s[kWf] = s[kWr] = vx / c.wheel_radius_m;
  return s;
}

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace

TEST_CASE("evidence: a pure delay line returns the command issued exactly `delay` earlier", "[evidence]") {
  DelayLine plain(0.0), delayed(0.06);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> issued;
  for (int k = 0; k < 100; ++k) {
    const double v = u(rng);
    issued.push_back(v);
    plain.issue(0.02 * k, v);
    delayed.issue(0.02 * k, v);
  }
  for (int i = 0; i < 1900; ++i) {  // 1 ms grid
    const double t = 0.001 * i;
    const double expect = t < 0.06 - 1e-9 ? 0.0 : issued[static_cast<std::size_t>(std::floor((t - 0.06) / 0.02 + 1e-9))];
    REQUIRE(delayed.value(t) == expect);
    (void)plain.value(t);
  }
}

TEST_CASE("evidence: with a pure steering and throttle delay the car's response is the undelayed one shifted exactly", "[evidence]") {
  const CarConstants c;
  auto drive = [&](double delay_s, std::vector<CarState>* out) {
    TruthEffects e;
    e.steer_delay_s = e.throttle_delay_s = delay_s;
    ActuatorChain chain(e, c);
    CarState s{};
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int k = 0; k < 150; ++k) {
      chain.issue(0.02 * k, 0.6 * u(rng), 0.3 + 0.4 * u(rng));
      for (int i = 0; i < 20; ++i) {
        const double t = 0.02 * k + 0.001 * i;
        const auto [angle, torque] = chain.step(t, 0.001, s[kWr] * c.wheel_radius_m);
        CarInputs in;
        in.wheel_angle_rad = angle;
        in.motor_torque_Nm = torque;
        s = rk4_step(c, s, in, 0.001);
        out->push_back(s);
      }
    }
  };
  std::vector<CarState> plain, delayed;
  drive(0.0, &plain);
  drive(0.08, &delayed);
  const std::size_t shift = 80;  // 0.08 s at 1 ms
  for (std::size_t i = 0; i < shift; ++i) REQUIRE(delayed[i][kVx] == 0.0);  // at rest until the first command arrives
  double worst = 0;
  for (std::size_t i = 0; i + shift < plain.size(); ++i)
    for (int j = 0; j < 8; ++j) worst = std::max(worst, std::abs(delayed[i + shift][static_cast<std::size_t>(j)] - plain[i][static_cast<std::size_t>(j)]));
  CHECK(worst < 1e-9);
  CHECK(plain.back()[kVx] > 1.0);  // it did drive
}

TEST_CASE("evidence: a servo rate limit bounds the steering slope and slews full lock in 2 / rate seconds", "[evidence]") {
  TruthEffects e;
  e.steer_rate_per_s = 2.5;
  const CarConstants c;
  ActuatorChain chain(e, c);
  double previous = 0, max_slope = 0;
  double reached_at = -1;
  chain.issue(0.0, -1, 0);
  chain.issue(1.0, 1, 0);
  for (int i = 0; i < 3000; ++i) {
    const double t = 0.001 * i;
    chain.step(t, 0.001, 0);
    const double s = chain.servo_position();
    max_slope = std::max(max_slope, std::abs(s - previous) / 0.001);
    if (reached_at < 0 && t >= 1.0 && s >= 1 - 1e-12) reached_at = t;
    previous = s;
  }
  CHECK(max_slope <= 2.5 + 1e-9);
  CHECK(max_slope >= 2.5 - 1e-9);
  CHECK(reached_at == Approx(1.0 + 2.0 / 2.5).margin(0.0015));
}

TEST_CASE("evidence: backlash holds the wheels while the servo moves inside the play", "[evidence]") {
  double out = 0;
  out = backlash(out, 0.04, 0.1);
  CHECK(out == 0.0);  // inside +-0.05
  out = backlash(out, 0.2, 0.1);
  CHECK(out == Approx(0.15));  // dragged by the edge
  out = backlash(out, 0.12, 0.1);
  CHECK(out == Approx(0.15));  // reversing: the play is crossed first
  out = backlash(out, 0.0, 0.1);
  CHECK(out == Approx(0.05));
}

TEST_CASE("evidence: drag along the velocity vector is -c |v| v and a coasting car follows v0 / (1 + c v0 t / m_eff)", "[evidence]") {
  const CarConstants c = frictionless_straight();
  CarInputs with, without;
  with.extra_drag_kgpm = 0.6;
  CarState s = rolling(4.0, c);
  s[kVy] = 1.2;
  const CarState a = car_derivative(c, s, with), b = car_derivative(c, s, without);
  const double speed = std::hypot(4.0, 1.2);
  CHECK(a[kVx] - b[kVx] == Approx(-0.6 * speed * 4.0 / c.mass_kg).epsilon(1e-12));
  CHECK(a[kVy] - b[kVy] == Approx(-0.6 * speed * 1.2 / c.mass_kg).epsilon(1e-12));

  // Coasting straight: the wheels spin down with the car, so the inertia is m + (I_f + I_r) / R^2.
  const double v0 = 8.0, drag = 0.6;
  const double m_eff = c.mass_kg + (c.front_wheel_inertia_kgm2 + c.rear_wheel_inertia_kgm2) / (c.wheel_radius_m * c.wheel_radius_m);
  CarState x = rolling(v0, c);
  for (int i = 0; i < 5000; ++i) x = rk4_step(c, x, with, 0.001);
  CHECK(x[kVx] == Approx(v0 / (1 + drag * v0 * 5.0 / m_eff)).epsilon(0.01));
  // Halving and doubling the speed scale the deceleration by 4: the v^2 law.
  const double d1 = car_derivative(c, rolling(3.0, c), with)[kVx], d2 = car_derivative(c, rolling(6.0, c), with)[kVx];
  CHECK(d2 / d1 == Approx(4.0).epsilon(1e-9));
}

TEST_CASE("evidence: a weight shift moves the static axle loads to m g (l_r - d) / L and the lever arms with them", "[evidence]") {
  const CarConstants c = frictionless_straight();
  const double wheelbase_m = c.lf_m + c.lr_m, weight_N = c.mass_kg * c.gravity_mps2;
  for (const double d : {0.0, 0.05, -0.04}) {
    INFO("d " << d << " m");
    CarInputs in;
    in.cg_rearward_m = d;
    CarForces f;
    car_derivative(c, rolling(3.0, c), in, &f);  // rolling straight: no friction, no pitch transfer
    CHECK(f.front.fz_N == Approx(weight_N * (c.lr_m - d) / wheelbase_m).epsilon(1e-9));
    CHECK(f.rear.fz_N == Approx(weight_N * (c.lf_m + d) / wheelbase_m).epsilon(1e-9));
  }
  // Turning at a steady wheel angle and side slip: the yaw moment's lever arms are l_f + d, l_r - d.
  CarState s = rolling(5.0, c);
  s[kVy] = 0.3;
  s[kR] = 0.4;
  CarInputs shifted;
  shifted.wheel_angle_rad = 0.1;
  shifted.cg_rearward_m = 0.05;
  CarForces f;
  const CarState ds = car_derivative(c, s, shifted, &f);
  const double lf = c.lf_m + 0.05, lr = c.lr_m - 0.05;
  // The rear tyre's side force at the rear contact: v_y - l_r r (the lever arm moved with the CG).
  const double cd = std::cos(0.1), sd = std::sin(0.1);
  CHECK(ds[kR] == Approx((lf * (f.front.fy_N * cd + f.front.fx_N * sd) - lr * f.rear.fy_N) / c.yaw_inertia_kgm2).epsilon(1e-9));
  CarInputs unshifted = shifted;
  unshifted.cg_rearward_m = 0;
  CHECK(std::abs(car_derivative(c, s, unshifted)[kR] - ds[kR]) > 0.1);
}

TEST_CASE("evidence: downforce c v^2 adds to the axle loads in the static split, and the side force with them", "[evidence]") {
  const CarConstants c = frictionless_straight();
  const double wheelbase_m = c.lf_m + c.lr_m, weight_N = c.mass_kg * c.gravity_mps2;
  for (const double v : {2.0, 6.0}) {
    INFO("v " << v << " m/s");
    CarInputs in;
    in.downforce_kgpm = 0.8;
    CarForces f;
    car_derivative(c, rolling(v, c), in, &f);
    const double down_N = 0.8 * v * v;
    CHECK(f.front.fz_N == Approx((weight_N + down_N) * c.lr_m / wheelbase_m).epsilon(1e-9));
    CHECK(f.rear.fz_N == Approx((weight_N + down_N) * c.lf_m / wheelbase_m).epsilon(1e-9));
  }
  // Sliding sideways at 6 m/s: the tyres' side force is mu x load, so it grows by the downforce's share.
  CarConstants grippy = c;
  grippy.mf_D = 1.0;
  CarState s = rolling(6.0, grippy);
  s[kVy] = 0.5;
  CarInputs none, down;
  down.downforce_kgpm = 0.8;
  CarForces f0, f1;
  car_derivative(grippy, s, none, &f0);
  car_derivative(grippy, s, down, &f1);
  CHECK(f1.rear.fy_N / f0.rear.fy_N == Approx(f1.rear.fz_N / f0.rear.fz_N).epsilon(1e-9));
  CHECK(f1.rear.fz_N > f0.rear.fz_N * 1.1);
}

TEST_CASE("evidence: effect sizes must be finite, and downforce not negative", "[evidence]") {
  TruthEffects e;
  CHECK_THROWS_WITH(set_truth_effects("downforce_kgpm=-0.5", &e), Catch::Contains("downforce must be >= 0"));
  CHECK_THROWS_WITH(set_truth_effects("extra_drag_kgpm=nan", &e), Catch::Contains("'extra_drag_kgpm=nan': value is not finite"));
  CHECK(e.downforce_kgpm == 0);
  CHECK(e.extra_drag_kgpm == 0);
  CHECK(set_truth_effects("downforce_kgpm=0.4", &e) == std::vector<std::string>{"aero_downforce"});
  CHECK(e.downforce_kgpm == 0.4);
}

// Closed form: a launch on Coulomb tyres (C = 1, B huge: mu = D at any real slip), no load
// transfer, a motor far stronger than the grip. Rear-wheel drive spins the rear wheels only: the
// rear axle's load m g l_f / L pushes the car and the rolling front wheels,
// a = D g (l_f / L) m / (m + I_f / R^2); with a share of the torque sent forward both axles spin: a = D g.
TEST_CASE("evidence: four-wheel drive sends its share of the torque forward, and a launch reaches D g instead of the rear axle's share", "[evidence]") {
  CarConstants c = frictionless_straight();
  c.mf_B = 1000;
  c.mf_C = 1;
  c.mf_D = 0.6;
  c.mf_E = c.mf_Sh = c.mf_Sv = 0;
  c.cg_height_m = 0;
  const double g = c.gravity_mps2;
  CarState s = rolling(2.0, c);
  s[kWr] += 10;
  s[kWf] += 5;
  CarInputs split;
  split.motor_torque_Nm = 300;
  split.front_torque_share = 0.3;
  CarForces f;
  const CarState ds = car_derivative(c, s, split, &f);
  CHECK(ds[kWf] * c.front_wheel_inertia_kgm2 + f.front.fx_N * c.wheel_radius_m == Approx(0.3 * 300).epsilon(1e-12));
  CHECK(ds[kWr] * c.rear_wheel_inertia_kgm2 + f.rear.fx_N * c.wheel_radius_m == Approx(0.7 * 300).epsilon(1e-12));
  CHECK(motor_wheel_speed(s, 0.3) == Approx(0.3 * s[kWf] + 0.7 * s[kWr]).epsilon(1e-15));
  auto launch_accel = [&](double share) {
    CarInputs in;
    in.motor_torque_Nm = 300;
    in.front_torque_share = share;
    CarState x = rolling(2.0, c);
    for (int i = 0; i < 500; ++i) x = rk4_step(c, x, in, 0.001);  // the driven wheels spin up
    const double v0 = x[kVx];
    for (int i = 0; i < 500; ++i) x = rk4_step(c, x, in, 0.001);
    return (x[kVx] - v0) / 0.5;
  };
  const double rolling_front_kg = c.front_wheel_inertia_kgm2 / (c.wheel_radius_m * c.wheel_radius_m);
  CHECK(launch_accel(0.0) ==
        Approx(c.mf_D * g * c.lf_m / (c.lf_m + c.lr_m) * c.mass_kg / (c.mass_kg + rolling_front_kg)).epsilon(0.02));
  CHECK(launch_accel(0.5) == Approx(c.mf_D * g).epsilon(0.02));
}

TEST_CASE("evidence: a grade adds -g sin(theta) along the slope and nothing across it", "[evidence]") {
  const CarConstants c = frictionless_straight();
  const double grade = 0.08, theta = std::atan(grade);
  double ax = 0, ay = 0;
  ground_gravity_body(grade, 0.0, 0.0, 9.81, &ax, &ay);  // heading uphill along +x
  CHECK(ax == Approx(-9.81 * std::sin(theta)).epsilon(1e-12));
  CHECK(ay == Approx(0.0).margin(1e-15));
  ground_gravity_body(0.0, grade, 0.0, 9.81, &ax, &ay);  // the slope rises to the car's left
  CHECK(ax == Approx(0.0).margin(1e-15));
  CHECK(ay == Approx(-9.81 * std::sin(theta)).epsilon(1e-12));
  ground_gravity_body(grade, 0.0, M_PI, 9.81, &ax, &ay);  // downhill
  CHECK(ax == Approx(9.81 * std::sin(theta)).epsilon(1e-12));

  CarInputs flat, hill;
  ground_gravity_body(grade, 0.0, 0.0, c.gravity_mps2, &hill.gravity_x_mps2, &hill.gravity_y_mps2);
  const CarState s = rolling(5.0, c);
  CHECK(car_derivative(c, s, hill)[kVx] - car_derivative(c, s, flat)[kVx] ==
        Approx(-c.gravity_mps2 * std::sin(theta)).epsilon(1e-12));
  // Rolling up a constant grade the car (with its wheels) decelerates at m g sin(theta) / m_eff.
  const double m_eff = c.mass_kg + (c.front_wheel_inertia_kgm2 + c.rear_wheel_inertia_kgm2) / (c.wheel_radius_m * c.wheel_radius_m);
  // (after the first second: the tyres need a little slip before they slow the wheels)
  CarState x = rolling(6.0, c);
  for (int i = 0; i < 1000; ++i) x = rk4_step(c, x, hill, 0.001);
  const double v1 = x[kVx];
  for (int i = 0; i < 1000; ++i) x = rk4_step(c, x, hill, 0.001);
  CHECK(v1 - x[kVx] == Approx(c.mass_kg * c.gravity_mps2 * std::sin(theta) / m_eff).epsilon(0.01));
}

TEST_CASE("evidence: the battery's motor torque solves its own voltage equation", "[evidence]") {
  const CarConstants c;
  Battery b;
  b.internal_resistance_fraction = 0.3;
  b.capacity_sag = 0.2;
  b.charge_used = 30;  // open circuit 1 - 0.2 * 30 / 60 = 0.9
  const double u = 0.6, rim = 6.0;
  const double t = b.torque_Nm(c, u, rim);
  // T = stall (u V - rim / v0) with V = 0.9 - 0.3 T / stall (per unit of the nominal voltage).
  const double v = 0.9 - 0.3 * t / c.stall_torque_Nm;
  CHECK(t == Approx(c.stall_torque_Nm * (u * v - rim / c.no_load_speed_mps)).epsilon(1e-12));
  CHECK(t < c.stall_torque_Nm * (u - rim / c.no_load_speed_mps));  // less than a fresh battery gives
  Battery fresh;
  CHECK(fresh.torque_Nm(c, u, rim) == Approx(c.stall_torque_Nm * (u - rim / c.no_load_speed_mps)));
  b.draw(c, 5.0, 2.0);
  CHECK(b.charge_used == Approx(30 + 0.5 * 2.0));
}

TEST_CASE("evidence: braking torque is the stall line with the command scaled by brake_torque_ratio", "[evidence]") {
  CarConstants c;
  c.brake_torque_ratio = 0.25;
  Battery b;
  b.internal_resistance_fraction = 0.3;  // the battery acts on drive, not on braking
  const double rim = 3.0;
  CHECK(b.torque_Nm(c, -0.8, rim) == Approx(c.stall_torque_Nm * (0.25 * -0.8 - rim / c.no_load_speed_mps)).epsilon(1e-12));
  CHECK(b.torque_Nm(c, 0.0, rim) == Approx(-c.stall_torque_Nm * rim / c.no_load_speed_mps).epsilon(1e-12));
  c.brake_torque_ratio = 1.0;
  CHECK(b.torque_Nm(c, -0.8, rim) == Approx(c.stall_torque_Nm * (-0.8 - rim / c.no_load_speed_mps)).epsilon(1e-12));
}

TEST_CASE("evidence: the car reads every constant of the nominal vehicle file and refuses keys it does not model", "[evidence]") {
  // The project's loader of the same file is the oracle: an effect-free evidence car must have
  // the nominal's constants, all of them.
  const std::string shipped = test::data_path("config/autorally_single_track.yaml");
  const SingleTrackParams p = load_single_track_params(shipped);
  const CarConstants c = read_car_constants(shipped);
  CHECK(c.mass_kg == p.mass_kg);
  CHECK(c.stall_torque_Nm == p.stall_torque_Nm);
  CHECK(c.no_load_speed_mps == p.no_load_speed_mps);
  CHECK(c.brake_torque_ratio == p.brake_torque_ratio);
  CHECK(c.max_steer_rad == p.max_steer_rad);
  CHECK(c.rolling_coefficient == p.rolling_resistance);
  CHECK(c.aero_drag_kgpm == p.aero_drag_kgpm);
  CHECK(c.mf_B == p.tyre.B);
  CHECK(c.mf_Sv == p.tyre.Sv);

  // Every key of the single-track parameter table, with a value of its own: none is refused.
  const std::string dir = (std::filesystem::temp_directory_path() / "mppi_evidence_keys_test").string();
  std::filesystem::create_directories(dir);
  SingleTrackParams q;
  std::ostringstream top, tyre;
  std::map<std::string, double> written;
  int k = 0;
  for (const ParamField& f : param_table(q)) {
    const std::string key = f.key;
    const double v = 0.5 + 0.01 * ++k;
    written[key] = v;
    if (key.rfind("tyre.", 0) == 0)
      tyre << "  " << key.substr(5) << ": " << v << "\n";
    else
      top << key << ": " << v << "\n";
  }
  const std::string all = dir + "/all.yaml";
  std::ofstream(all) << top.str() << "tyre:\n" << tyre.str();
  const CarConstants every = read_car_constants(all);
  CHECK(every.brake_torque_ratio != CarConstants{}.brake_torque_ratio);
  // the rear tyre: the front's Magic Formula with B, C, D times the file's factors
  CHECK(every.rear_B_factor == written.at("rear_tyre_B_scale"));
  CHECK(every.rear_C_factor == written.at("rear_tyre_C_scale"));
  CHECK(every.rear_D_factor == written.at("rear_tyre_D_scale"));
  for (double slip : {0.02, 0.1, 0.4}) {
    const double B = every.mf_B * written.at("rear_tyre_B_scale"), C = every.mf_C * written.at("rear_tyre_C_scale"),
                 D = every.mf_D * written.at("rear_tyre_D_scale"), x = slip - every.mf_Sh;
    // the paper's form: mu = D sin(C atan(B x - E (B x - atan x))) + Sv, x = slip - Sh
    const double closed_form = D * std::sin(C * std::atan(B * x - every.mf_E * (B * x - std::atan(x)))) + every.mf_Sv;
    CHECK(tyre_mu(every, slip, /*rear=*/true) == Approx(closed_form).epsilon(1e-12));
  }

  const std::string unknown = dir + "/unknown.yaml";
  std::ofstream(unknown) << "mass_kg: 20\nclutch_slip: 0.1\n";
  CHECK_THROWS_WITH(read_car_constants(unknown), Catch::Contains(unknown) && Catch::Contains("clutch_slip"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("evidence: recordings are reproducible by seed and differ between seeds", "[evidence]") {
  const std::string dir = (std::filesystem::temp_directory_path() / "mppi_evidence_test").string();
  std::filesystem::remove_all(dir);
  EvidenceOptions o;
  o.duration_s = 12;
  o.truth_names = set_truth_effects("steer_delay_s=0.05,grip_patch_scale=0.6", &o.truth);
  o.seed = 4;
  const EvidenceResult a = generate_evidence(o, dir + "/a.csv");
  const EvidenceResult b = generate_evidence(o, dir + "/b.csv");
  o.seed = 5;
  const EvidenceResult c = generate_evidence(o, dir + "/c.csv");
  auto body = [](const std::string& p) {
    const std::string s = slurp(p);
    return s.substr(s.find("\nt,"));
  };
  CHECK(body(a.csv) == body(b.csv));
  CHECK(body(a.clean_csv) == body(b.clean_csv));
  CHECK(body(a.csv) != body(c.csv));
  const sim::Recording rec = sim::RecordingReader::read(a.csv), clean = sim::RecordingReader::read(a.clean_csv);
  CHECK(rec.rows() == clean.rows());
  CHECK(rec.rows() > 500);
  const std::string truth = slurp(a.truth_json);
  CHECK(truth.find("\"steer_delay\"") != std::string::npos);
  CHECK(truth.find("\"grip_patch\"") != std::string::npos);  // the grip patches: a place-dependent candidate
  std::filesystem::remove_all(dir);
}

TEST_CASE("evidence: an effect-free recording is predicted by the nominal built from the vehicle file it names", "[evidence]") {
  // The nominal single-track (other code, another integrator) built from the file in the truth
  // file predicts the car's noise-free states for 1 s about as well as its own noise allows; the
  // library defaults, a different car since the shipped file was calibrated, do not.
  const std::string dir = (std::filesystem::temp_directory_path() / "mppi_evidence_nominal_test").string();
  std::filesystem::remove_all(dir);
  EvidenceOptions o;
  o.duration_s = 20;
  o.seed = 3;
  const EvidenceResult r = generate_evidence(o, dir + "/clean.csv");
  CHECK(r.vehicle_yaml == o.vehicle_yaml + sim::data_file("config/autorally_single_track.yaml"));
  CHECK(slurp(r.truth_json).find("\"vehicle_params\"") != std::string::npos);
  const diagnose::PreparedRecording d = diagnose::load_recording(r.clean_csv);
  const std::vector<char> all(d.rows(), 1);
  auto nrmse_1s = [&](const std::string& params) {
    const auto family = diagnose::make_model_family("single-track", params);
    return diagnose::horizon_metrics(*family->make({}), d, all, {1.0}, 5, {})[0].normalized_rmse;
  };
  const double same = nrmse_1s(r.vehicle_yaml), defaults = nrmse_1s("");
  INFO("1-s normalised RMSE: nominal from " << r.vehicle_yaml << " " << same << ", library defaults " << defaults);
  CHECK(same < 0.1);
  CHECK(defaults > 3 * same);
  std::filesystem::remove_all(dir);
}

TEST_CASE("evidence: a recording at 25 or 100 Hz is the same drive at that rate", "[evidence]") {
  // The driver acts and the log writes at the rate asked for; the rows are 1 / rate apart, the
  // nominal (other code) predicts the noise-free states of the effect-free car as well as at
  // 50 Hz, and the drivers, whose delays and rates are in seconds, drive at the same pace.
  const std::string dir = (std::filesystem::temp_directory_path() / "mppi_evidence_rate_test").string();
  std::filesystem::remove_all(dir);
  auto run = [&](double rate_hz, const std::string& driver) {
    EvidenceOptions o;
    o.duration_s = 20;
    o.seed = 3;
    o.driver = driver;
    o.log_dt_s = log_interval_s(rate_hz);
    return generate_evidence(o, dir + "/" + driver + std::to_string(static_cast<int>(rate_hz)) + ".csv");
  };
  auto mean_speed = [](const diagnose::PreparedRecording& d) {
    double sum = 0;
    for (std::size_t k = 0; k < d.rows(); ++k) sum += std::hypot(d.vx[k], d.vy[k]);
    return sum / static_cast<double>(d.rows());
  };
  for (const std::string driver : {"pursuit", "human"}) {
    const diagnose::PreparedRecording at50 = diagnose::load_recording(run(50, driver).clean_csv);
    for (double rate : {25.0, 100.0}) {
      const EvidenceResult r = run(rate, driver);
      const diagnose::PreparedRecording d = diagnose::load_recording(r.clean_csv);
      INFO(driver << " at " << rate << " Hz");
      // 20 s of rows, less the 0.1 % the generator drops from the files
      CHECK(d.rows() <= static_cast<std::size_t>(std::lround(20 * rate)));
      CHECK(d.rows() >= static_cast<std::size_t>(std::lround(0.99 * 20 * rate)));
      CHECK(d.dt_s == Approx(1.0 / rate).epsilon(1e-9));
      const std::vector<char> all(d.rows(), 1);
      const auto family = diagnose::make_model_family("single-track", r.vehicle_yaml);
      CHECK(diagnose::horizon_metrics(*family->make({}), d, all, {1.0}, 5, {})[0].normalized_rmse < 0.1);
      // The pursuit driver crashes a few times in 20 s and restarts from rest each time, so its
      // mean speed depends on how many: a wider band.
      CHECK(mean_speed(d) == Approx(mean_speed(at50)).epsilon(driver == "human" ? 0.1 : 0.2));
    }
  }
  CHECK_THROWS_WITH(log_interval_s(33), Catch::Contains("the log rate 33 Hz is not a whole number of 0.001 s"));
  CHECK_THROWS_WITH(log_interval_s(2), Catch::Contains("[5, 500] Hz, got 2"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("evidence: the generator's sources include nothing of the diagnosis or the effect table", "[evidence]") {
  const std::filesystem::path folder = std::filesystem::path(test::data_path("..")) / "evidence";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string text = slurp(entry.path().string());
    ++files;
    INFO(entry.path().string());
    CHECK(text.find("#include \"dynamics/") == std::string::npos);
    CHECK(text.find("#include \"diagnose/") == std::string::npos);
    CHECK(text.find("with_effects") == std::string::npos);
    CHECK(text.find("corrected_model") == std::string::npos);
  }
  CHECK(files >= 8);
}
