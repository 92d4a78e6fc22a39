// The limit lap (sim/limit_lap.hpp): the QSS speed profile against closed forms and an
// independent integration, the friction ellipse, the racing line against the track's
// boundaries and the centreline, and refused input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "dynamics/vehicle_params.hpp"
#include "error_of.hpp"
#include "sim/limit_lap.hpp"
#include "sim/qss_speed_profile.hpp"
#include "sim/racing_line.hpp"
#include "sim/track.hpp"
#include "test_data.hpp"

using namespace mppi::sim;
using Catch::Matchers::Contains;
using mppi::test::error_of;

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A plain car: 20 kg, mu 0.8, no drag or rolling resistance.
CarLimits plain_car() {
  CarLimits c;
  c.mass_kg = 20.0;
  c.gravity_mps2 = 9.81;
  c.mu = 0.8;
  c.drive_force_N = 100.0;
  c.brake_force_N = 100.0;
  return c;
}

const Track& track_named(const std::string& name) {
  static std::vector<std::pair<std::string, Track>> cache;
  for (const auto& [n, t] : cache)
    if (n == name) return t;
  TrackOptions o;
  o.data_dir = mppi::test::data_path("");
  cache.emplace_back(name, Track::load(name, o));
  return cache.back().second;
}

mppi::SingleTrackParams default_plant() {
  return mppi::load_single_track_params(mppi::test::data_path("config/autorally_single_track.yaml"));
}

// Crossing-number point-in-polygon and point-to-segment distance, written here (not the
// library's) so that the racing line is checked independently.
bool inside(const Polyline& poly, Vec2 p) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2 a = poly[i], b = poly[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}
double distance_to_polygon(const Polyline& poly, Vec2 p) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2 a = poly[i], b = poly[(i + 1) % poly.size()];
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double t = std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
    best = std::min(best, std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy));
  }
  return best;
}
}  // namespace

TEST_CASE("qss: a circle is driven at sqrt(mu g R) all the way round", "[limit_lap]") {
  const CarLimits car = plain_car();
  const double radius = 10.0;
  const int n = 400;
  const std::vector<double> ds(n, 2 * kPi * radius / n), kappa(n, 1.0 / radius);
  const QssProfile p = qss_speed_profile(ds, kappa, car);
  const double v = std::sqrt(car.mu * car.gravity_mps2 * radius);
  for (double s : p.speed_mps) REQUIRE(s == Approx(v).epsilon(1e-9));
  CHECK(p.time_s == Approx(2 * kPi * radius / v).epsilon(1e-9));
  // The same on a polygon through the circle: lap_on_line's curvature is the circle's.
  Polyline circle;
  for (int i = 0; i < n; ++i) circle.push_back({radius * std::cos(2 * kPi * i / n), radius * std::sin(2 * kPi * i / n)});
  const LimitLap lap = lap_on_line(circle, car);
  for (double k : lap.curvature_1pm) REQUIRE(k == Approx(1.0 / radius).epsilon(1e-9));
  CHECK(lap.lap_time_s == Approx(2 * kPi * radius / v).epsilon(1e-4));
  CHECK(lap.mean_speed_mps == Approx(v).epsilon(1e-9));
}

TEST_CASE("qss: from rest under a constant force the car reaches v after v^2 / (2 F/m)", "[limit_lap]") {
  CarLimits car = plain_car();
  car.closed = false;
  car.drive_force_N = 50.0;  // no-load speed infinite: a constant force
  const double a = car.drive_force_N / car.mass_kg;
  const int n = 1001;
  const std::vector<double> ds(n - 1, 0.01), kappa(n, 0.0);
  const QssProfile p = qss_speed_profile(ds, kappa, car);
  for (int i = 0; i < n; ++i) {
    const double s = 0.01 * i;
    // The distance to reach the speed v is v^2 / (2 a).
    REQUIRE(p.speed_mps[i] * p.speed_mps[i] / (2 * a) == Approx(s).margin(1e-9));
  }
  CHECK(p.time_s == Approx(std::sqrt(2 * 10.0 / a)).epsilon(1e-9));
}

TEST_CASE("qss: the forward pass on the drive line matches an integration of m dv/dt = F(v) - c v^2", "[limit_lap]") {
  CarLimits car = plain_car();
  car.closed = false;
  car.mass_kg = 21.88;
  car.drive_force_N = 28.54 / 0.0975;  // the calibrated stall torque / R
  car.no_load_speed_mps = 31.35;
  car.drag_kgpm = 0.2543;
  const double length = 60.0, spacing = 0.05;
  const int n = static_cast<int>(length / spacing) + 1;
  const std::vector<double> ds(n - 1, spacing), kappa(n, 0.0);
  const QssProfile p = qss_speed_profile(ds, kappa, car);
  // Independent: RK4 in time of (x, v), the speed read where x passes each check point.
  auto dv = [&](double v) {
    return (car.drive_force_N * (1 - v / car.no_load_speed_mps) - car.drag_kgpm * v * v) / car.mass_kg;
  };
  double x = 0, v = 0, t = 0;
  const double dt = 1e-4;
  int checked = 0;
  double time_at_end = 0;
  for (double target = 1.0; target <= length; target += 1.0) {
    while (x < target) {
      const double k1v = dv(v), k1x = v;
      const double k2v = dv(v + 0.5 * dt * k1v), k2x = v + 0.5 * dt * k1v;
      const double k3v = dv(v + 0.5 * dt * k2v), k3x = v + 0.5 * dt * k2v;
      const double k4v = dv(v + dt * k3v), k4x = v + dt * k3v;
      x += dt / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
      v += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      t += dt;
    }
    const int i = static_cast<int>(std::lround(target / spacing));
    REQUIRE(p.speed_mps[i] == Approx(v).epsilon(2e-3));
    ++checked;
    time_at_end = t;
  }
  CHECK(checked == 60);
  CHECK(p.time_s == Approx(time_at_end).epsilon(2e-3));
  CHECK(p.speed_mps.back() > 10.0);  // the drive line, not the start, sets these speeds
}

TEST_CASE("qss: a standing start loses what an integration from rest of the drive line says", "[limit_lap]") {
  // The calibrated car's drive line and rear-axle grip, from its file, written here: on a circle of
  // 100 m with the friction made large, the lateral acceleration takes nothing from the drive.
  const mppi::SingleTrackParams p = default_plant();
  CarLimits car;
  car.mass_kg = p.mass_kg;
  car.gravity_mps2 = p.gravity_mps2;
  car.mu = 50.0;
  car.drive_force_N = p.stall_torque_Nm / p.wheel_radius_m;
  car.no_load_speed_mps = p.no_load_speed_mps;
  car.traction_grip_N = (p.tyre.D + p.tyre.Sv) * p.mass_kg * p.gravity_mps2 * p.cg_to_front_axle_m / p.wheelbase_m();
  car.brake_force_N = car.drive_force_N;
  car.drag_kgpm = p.aero_drag_kgpm;
  car.rolling_force_N = p.rolling_resistance * p.mass_kg * p.gravity_mps2;
  Polyline circle;
  const int vertices = 1257;  // 0.5 m apart
  for (int i = 0; i < vertices; ++i)
    circle.push_back({100.0 * std::cos(2 * kPi * i / vertices), 100.0 * std::sin(2 * kPi * i / vertices)});
  const LimitLap flying = lap_on_line(circle, car);
  const LimitLap standing = standing_lap_on_line(circle, car);
  REQUIRE(standing.standing_start);
  REQUIRE(standing.speed_mps.size() == circle.size() + 1);
  CHECK(standing.speed_mps.front() == 0.0);
  CHECK(standing.length_m == Approx(flying.length_m).epsilon(1e-12));
  // Independent: RK4 in time of m dv/dt = min(F(v), grip) - c v^2 - rolling from rest until the
  // lap's length is covered; the flying lap at the speed where the drive meets the resistances.
  auto dv = [&](double v) {
    const double drive = std::min(car.drive_force_N * (1 - v / car.no_load_speed_mps), car.traction_grip_N);
    return (drive - car.drag_kgpm * v * v - car.rolling_force_N) / car.mass_kg;
  };
  double x = 0, v = 0, t = 0;
  const double dt = 1e-4;
  while (x < flying.length_m) {
    const double k1v = dv(v), k1x = v;
    const double k2v = dv(v + 0.5 * dt * k1v), k2x = v + 0.5 * dt * k1v;
    const double k3v = dv(v + 0.5 * dt * k2v), k3x = v + 0.5 * dt * k2v;
    const double k4v = dv(v + dt * k3v), k4x = v + dt * k3v;
    x += dt / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    t += dt;
  }
  double lo = 0, hi = car.no_load_speed_mps;
  for (int i = 0; i < 100; ++i) (dv(0.5 * (lo + hi)) > 0 ? lo : hi) = 0.5 * (lo + hi);
  const double flying_oracle_s = flying.length_m / lo;
  const double lost_oracle_s = t - flying_oracle_s;
  INFO("standing " << standing.lap_time_s << " s (oracle " << t << "), flying " << flying.lap_time_s << " s (oracle "
                   << flying_oracle_s << "), time lost " << standing.lap_time_s - flying.lap_time_s << " s (oracle "
                   << lost_oracle_s << ")");
  CHECK(lost_oracle_s > 2.0);  // the start matters here
  CHECK(flying.lap_time_s == Approx(flying_oracle_s).epsilon(1e-4));
  CHECK(standing.lap_time_s == Approx(t).epsilon(1e-3));
  CHECK(standing.lap_time_s - flying.lap_time_s == Approx(lost_oracle_s).epsilon(1e-2));
}

TEST_CASE("qss: the standing-start limit lap is slower than the flying one and joins it", "[limit_lap]") {
  const Track& oval = track_named("gazebo");
  const mppi::SingleTrackParams car = default_plant();
  const LimitLap flying = limit_lap(oval, car);
  const LimitLap standing = standing_limit_lap(oval, car);
  INFO("flying " << flying.lap_time_s << " s, standing " << standing.lap_time_s << " s");
  CHECK(standing.standing_start);
  CHECK_FALSE(flying.standing_start);
  CHECK(standing.speed_mps.front() == 0.0);
  // On one line (the standing lap's), the standing profile never exceeds the flying one.
  RacingLineOptions line_options;
  line_options.margin_m = 0.5;
  line_options.length_weight_1pm2 = standing.length_weight_1pm2;
  const Polyline line = racing_line(oval, line_options).line;
  const LimitLap on_line_flying = lap_on_line(line, car_limits(car));
  const LimitLap on_line_standing = standing_lap_on_line(line, car_limits(car));
  CHECK(on_line_standing.lap_time_s == Approx(standing.lap_time_s).epsilon(1e-12));
  for (std::size_t i = 0; i < line.size(); ++i) REQUIRE(on_line_standing.speed_mps[i] <= on_line_flying.speed_mps[i] + 1e-12);
  // The time lost is at least what the best launch loses against the flying lap's slowest speed
  // v_m over the first v_line^2 / (2 a) metres: from rest at most sqrt(2 a x) with a the drive's
  // grip over the mass, so the loss is >= the integral of 1 / sqrt(2 a x) - 1 / v_m up to
  // v_m^2 / (2 a): v_m / a - v_m / (2 a) = v_m / (2 a). (The flying lap on the best line is no slower.)
  const double a_max = car_limits(car).traction_grip_N / car.mass_kg;
  const double reach_m = on_line_flying.speed_mps.front() * on_line_flying.speed_mps.front() / (2 * a_max);
  double v_m = on_line_flying.speed_mps.front();
  for (std::size_t i = 0; i < line.size() && on_line_flying.s_m[i] <= reach_m + 1.0; ++i)
    v_m = std::min(v_m, on_line_flying.speed_mps[i]);
  INFO("least loss " << v_m / (2 * a_max) << " s");
  CHECK(standing.lap_time_s - flying.lap_time_s >= v_m / (2 * a_max));
  // It catches the flying profile before the line again and ends at its speed there.
  CHECK(on_line_standing.speed_mps.back() == Approx(on_line_flying.speed_mps.front()).epsilon(1e-9));
}

TEST_CASE("qss: braking from v0 to rest takes v0^2 / (2 a_brake)", "[limit_lap]") {
  CarLimits car = plain_car();
  car.closed = false;
  car.drive_force_N = 0.0;  // coasting at v0 until the brake point
  car.brake_force_N = 60.0;
  car.start_speed_mps = 10.0;
  car.end_speed_mps = 0.0;
  const double a_brake = car.brake_force_N / car.mass_kg, length = 50.0, spacing = 0.01;
  const int n = static_cast<int>(length / spacing) + 1;
  const std::vector<double> ds(n - 1, spacing), kappa(n, 0.0);
  const QssProfile p = qss_speed_profile(ds, kappa, car);
  int first_braking = -1;
  for (int i = 0; i < n; ++i)
    if (first_braking < 0 && p.speed_mps[i] < car.start_speed_mps - 1e-9) first_braking = i;
  REQUIRE(first_braking > 0);
  const double braking_distance = length - spacing * (first_braking - 1);
  CHECK(braking_distance == Approx(10.0 * 10.0 / (2 * a_brake)).margin(spacing));
  for (int i = first_braking; i < n; ++i)
    REQUIRE(p.speed_mps[i] == Approx(std::sqrt(2 * a_brake * (length - spacing * i))).margin(1e-9));
  CHECK(p.speed_mps.back() == 0.0);
}

TEST_CASE("qss: entering a corner, (a_x, a_y) stay inside the friction ellipse", "[limit_lap]") {
  CarLimits car = plain_car();
  car.closed = false;
  car.drive_force_N = 400.0;
  car.brake_force_N = 400.0;  // grip, not the brake, limits
  car.traction_grip_N = car.brake_grip_N = 0.6 * car.mu * car.mass_kg * car.gravity_mps2;
  car.start_speed_mps = 12.0;
  // 20 m straight, a 10 m clothoid to radius 5 m, 15 m of arc.
  const double spacing = 0.05;
  std::vector<double> kappa;
  for (double s = 0; s <= 45.0 + 1e-9; s += spacing)
    kappa.push_back(s < 20 ? 0.0 : std::min(1.0, (s - 20) / 10.0) / 5.0);
  const std::vector<double> ds(kappa.size() - 1, spacing);
  const QssProfile p = qss_speed_profile(ds, kappa, car);
  const double ay_max = car.mu * car.gravity_mps2, ax_max = car.traction_grip_N / car.mass_kg;
  int combined = 0;
  double worst = 0;
  for (std::size_t i = 0; i + 1 < kappa.size(); ++i) {
    const double rx = p.ax_mps2[i] / ax_max, ry = p.ay_mps2[i] / ay_max;
    worst = std::max(worst, rx * rx + ry * ry);
    if (std::abs(rx) > 0.2 && std::abs(ry) > 0.2) ++combined;
  }
  CHECK(worst <= 1.0 + 1e-9);
  CHECK(worst > 0.99);     // the profile uses the grip it has
  CHECK(combined > 10);    // trail-braking into the clothoid: both at once
}

TEST_CASE("qss: car_limits of the calibrated AutoRally", "[limit_lap]") {
  mppi::SingleTrackParams p = default_plant();
  const CarLimits c = car_limits(p);
  // C > 1: the Magic Formula's sine reaches 1, so the peak is D + Sv (tanh(s / 0.1) ~ 1 there).
  CHECK(c.mu == Approx(p.tyre.D + p.tyre.Sv).epsilon(1e-4));
  const double weight = p.mass_kg * p.gravity_mps2;
  CHECK(c.traction_grip_N == Approx(c.mu * weight * p.cg_to_front_axle_m / p.wheelbase_m()).epsilon(1e-12));
  CHECK(c.drive_force_N == Approx(p.stall_torque_Nm / p.wheel_radius_m));
  CHECK(c.brake_force_N == Approx(p.stall_torque_Nm / p.wheel_radius_m * p.brake_torque_ratio));
  CHECK(c.drag_kgpm == p.aero_drag_kgpm);
  // Four-wheel drive, even split: the lighter front axle slips first.
  p.front_drive_share = 0.5;
  CHECK(car_limits(p).traction_grip_N ==
        Approx(car_limits(p).mu * weight * p.cg_to_rear_axle_m / p.wheelbase_m() / 0.5).epsilon(1e-12));
}

TEST_CASE("limit lap: the racing line stays on the track and beats the centreline", "[limit_lap]") {
  const mppi::SingleTrackParams plant = default_plant();
  const LimitLapOptions options;
  const double margin = options.car_half_width_m + options.safety_margin_m;
  for (const std::string name : {"gazebo", "marietta", "ccrf"}) {
    CAPTURE(name);
    const Track& track = track_named(name);
    const LimitLap lap = limit_lap(track, plant, options);
    const LimitLap centre = centreline_lap(track, plant, options);
    std::printf("limit lap %-8s %6.2f s, mean %5.2f m/s, max %5.2f, min %5.2f, line %6.1f m (length weight %.2f) | "
                "centreline %6.2f s\n",
                name.c_str(), lap.lap_time_s, lap.mean_speed_mps, lap.max_speed_mps, lap.min_speed_mps, lap.length_m,
                lap.length_weight_1pm2, centre.lap_time_s);
    CHECK(lap.lap_time_s < centre.lap_time_s);
    // The limit lap's line and the minimum-curvature line keep the margin from both boundaries.
    for (double weight : {lap.length_weight_1pm2, 0.0}) {
      RacingLineOptions line_options;
      line_options.margin_m = margin;
      line_options.length_weight_1pm2 = weight;
      const RacingLine line = racing_line(track, line_options);
      for (std::size_t i = 0; i < line.line.size(); ++i) {
        const Vec2 p = line.line[i];
        CAPTURE(weight, i, p.x, p.y);
        REQUIRE(inside(track.outer(), p));
        REQUIRE(!inside(track.inner(), p));
        REQUIRE(distance_to_polygon(track.outer(), p) >= margin - 1e-9);
        REQUIRE(distance_to_polygon(track.inner(), p) >= margin - 1e-9);
      }
      if (weight == lap.length_weight_1pm2) CHECK(lap.x_m.front() == line.line.front().x);  // the lap's line
    }
    if (name == "gazebo") {
      // Turns of 5-6 m radius at mu 0.77: 6-7 m/s; the network at 6 m/s laps in 10.3-10.5 s.
      CHECK(lap.lap_time_s > 4.0);
      CHECK(lap.lap_time_s < 10.3);
      CHECK(lap.mean_speed_mps > 6.0);
      CHECK(lap.max_speed_mps < 19.6);  // below the calibrated car's top speed
    }
  }
}

TEST_CASE("limit lap: bad input is refused with the reason", "[limit_lap]") {
  const std::vector<double> ds(4, 1.0), kappa(4, 0.1);
  CarLimits car = plain_car();
  CHECK_THAT(error_of([&] { qss_speed_profile({}, {}, car); }), Contains("at least 2 stations"));
  CHECK_THAT(error_of([&] { qss_speed_profile({1.0, 1.0}, kappa, car); }), Contains("ds_m needs 4"));
  CHECK_THAT(error_of([&] { qss_speed_profile(ds, {0.1, kNaN, 0.1, 0.1}, car); }), Contains("curvature_1pm[1]"));
  CHECK_THAT(error_of([&] { qss_speed_profile({1.0, 0.0, 1.0, 1.0}, kappa, car); }), Contains("ds_m[1]"));
  car.mass_kg = 0.0;
  CHECK_THAT(error_of([&] { qss_speed_profile(ds, kappa, car); }), Contains("mass_kg"));
  car = plain_car();
  car.mu = -0.5;
  CHECK_THAT(error_of([&] { qss_speed_profile(ds, kappa, car); }), Contains("mu"));
  car = plain_car();
  car.drag_kgpm = kNaN;
  CHECK_THAT(error_of([&] { qss_speed_profile(ds, kappa, car); }), Contains("drag_kgpm"));
  car = plain_car();  // a closed straight with nothing to bound the speed
  CHECK_THAT(error_of([&] { qss_speed_profile(ds, {0.0, 0.0, 0.0, 0.0}, car); }), Contains("nothing bounds"));

  mppi::SingleTrackParams plant = default_plant();
  const Track& gazebo = track_named("gazebo");
  LimitLapOptions options;
  options.car_half_width_m = kNaN;
  CHECK_THAT(error_of([&] { limit_lap(gazebo, plant, options); }), Contains("car_half_width_m"));
  options = {};
  options.safety_margin_m = 5.0;
  CHECK_THAT(error_of([&] { limit_lap(gazebo, plant, options); }), Contains("less than twice the margin"));
  options = {};
  options.length_weights_1pm2 = {};
  CHECK_THAT(error_of([&] { limit_lap(gazebo, plant, options); }), Contains("length_weights_1pm2"));
  options = {};
  plant.mass_kg = -1.0;
  CHECK_THAT(error_of([&] { limit_lap(gazebo, plant, options); }), Contains("mass_kg"));
}
