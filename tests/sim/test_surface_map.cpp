// Surface maps (sim/surface_map.hpp) and the single-track plant on them (sim/surface_plant.hpp)
// against closed forms: patch values and blends, raised-cosine hills, bilinear image lookup,
// a constant grade changing the acceleration by g sin(theta), and a low-grip patch capping the
// tyre force at mu_peak x scale x F_z on the patch only. The diagnosis' ground_bump effect is
// checked against the surface plant's hill (its own slope by central differences).
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>

#include "base/error.hpp"
#include "dynamics/single_track.hpp"
#include "dynamics/with_effects.hpp"
#include "sim/closed_loop.hpp"
#include "sim/recording.hpp"
#include "sim/surface_map.hpp"
#include "sim/surface_plant.hpp"
#include "test_data.hpp"

using namespace mppi;
using namespace mppi::sim;

namespace {

std::string temp_file(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "mppi_surface_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

}  // namespace

TEST_CASE("surface map: disc patches, edges and hills take their closed-form values", "[surface]") {
  const std::string path = temp_file("discs.yaml", R"(grip:
  default: 0.9
  patches:
    - {centre_m: [2.0, 3.0], radius_m: 1.0, value: 0.5, edge_m: 2.0}
elevation:
  patches:
    - {centre_m: [-5.0, 0.0], radius_m: 4.0, value: 0.6}
)");
  const SurfaceMap m = SurfaceMap::load(path);
  CHECK(m.grip(2.0, 3.0) == Approx(0.5));
  CHECK(m.grip(2.9, 3.0) == Approx(0.5));            // inside the radius
  CHECK(m.grip(2.0 + 1 + 1.0, 3.0) == Approx(0.7));  // half way through the edge: smoothstep 0.5
  CHECK(m.grip(2.0 + 1 + 2.5, 3.0) == Approx(0.9));  // beyond the edge: the default
  CHECK(m.elevation_m(-5.0, 0.0) == Approx(0.6));
  CHECK(m.elevation_m(-5.0, 2.0) == Approx(0.3));    // r = R/2: 0.6 (1 + cos(pi/2)) / 2
  CHECK(m.elevation_m(-5.0, 4.5) == Approx(0.0));
  // The slope of the raised cosine at r = R/2: -0.6 pi / (2 R) sin(pi/2) = -0.2356 per metre.
  CHECK(m.slope(-5.0, 2.0).y == Approx(-0.6 * M_PI / 8.0).epsilon(1e-3));
}

TEST_CASE("surface map: arc-length patches follow the track's centreline", "[surface]") {
  const std::string path = temp_file("arc.yaml", "track: gazebo\ngrip:\n  patches:\n    - {arc_m: [10.0, 20.0], value: 0.4}\n");
  const SurfaceMap m = SurfaceMap::load(path);
  const Track t = Track::load("gazebo");
  auto at_arc = [&](double s) {
    const auto& arc = t.centreline_arc_m();
    std::size_t i = 0;
    while (arc[i + 1] < s) ++i;
    const double f = (s - arc[i]) / (arc[i + 1] - arc[i]);
    const Vec2 a = t.centreline()[i], b = t.centreline()[(i + 1) % t.centreline().size()];
    return Vec2{a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)};
  };
  for (double s : {10.5, 15.0, 19.5}) CHECK(m.grip(at_arc(s).x, at_arc(s).y) == Approx(0.4));
  for (double s : {5.0, 25.0, 40.0}) CHECK(m.grip(at_arc(s).x, at_arc(s).y) == Approx(1.0));
  CHECK_THROWS_AS(SurfaceMap::load(temp_file("arc_no_track.yaml", "grip:\n  patches:\n    - {arc_m: [1, 2], value: 0.4}\n")),
                  Error);
}

TEST_CASE("surface map: a grayscale image is read bottom row = lowest y and interpolated bilinearly", "[surface]") {
  // 3 x 2 binary PGM: top row 0 255 0, bottom row 255 0 255.
  std::string pgm = "P5\n3 2\n255\n";
  for (unsigned char v : {0, 255, 0, 255, 0, 255}) pgm.push_back(static_cast<char>(v));
  temp_file("grip.pgm", pgm);
  const SurfaceMap m = SurfaceMap::load(temp_file("image.yaml",
      "grip:\n  image: grip.pgm\n  origin_m: [10.0, 20.0]\n  resolution_m: 2.0\n  black: 0.5\n  white: 1.0\n  default: 0.8\n"));
  // Cell centres: x 11, 13, 15; y 21 (bottom row), 23 (top row).
  CHECK(m.grip(11.0, 21.0) == Approx(1.0));
  CHECK(m.grip(13.0, 21.0) == Approx(0.5));
  CHECK(m.grip(11.0, 23.0) == Approx(0.5));
  CHECK(m.grip(12.0, 22.0) == Approx(0.75));       // the mean of the four around it
  CHECK(m.grip(11.5, 21.0) == Approx(0.875));      // a quarter of the way along the bottom row
  CHECK(m.grip(100.0, 0.0) == Approx(0.8));        // off the image: the default
}

TEST_CASE("surface map: malformed files are errors naming the key", "[surface]") {
  auto message = [](const std::string& text) {
    try {
      SurfaceMap::load(temp_file("bad.yaml", text));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(message("grip:\n  patches:\n    - {centre_m: [0, 0], radius_m: 1, value: -1}\n").find("grip.patches[0].value") != std::string::npos);
  CHECK(message("grip:\n  bogus: 1\n").find("grip.bogus") != std::string::npos);
  CHECK(message("elevation:\n  grade: [0.1]\n").find("elevation.grade") != std::string::npos);
}

TEST_CASE("surface plant: a constant grade changes the acceleration by g sin(theta) along the slope", "[surface]") {
  const double grade = 0.1, theta = std::atan(grade);
  SurfaceLayer elevation;
  elevation.grade_x = grade;
  SurfaceLayer grip;
  grip.default_value = 1.0;
  auto hill = std::make_shared<const SurfaceMap>(grip, elevation);
  auto flat = std::make_shared<const SurfaceMap>();
  const SingleTrackParams p;
  const SingleTrackOnSurface on_hill(p, hill), on_flat(p, flat);
  for (double yaw : {0.0, M_PI, M_PI / 2}) {
    VehicleState s;
    s.vx_mps = 5.f;
    s.yaw_rad = static_cast<float>(yaw);
    float a[SingleTrack::kNx], b[SingleTrack::kNx];
    on_hill.init_state(s, a);
    on_flat.init_state(s, b);
    float u[2] = {0.f, 0.2f};
    const float dt = 0.002f;
    on_hill.step<1>(Batch<SingleTrack::kNx, 1>{a}, ConstBatch<2, 1>{u}, dt, nullptr);
    on_flat.step<1>(Batch<SingleTrack::kNx, 1>{b}, ConstBatch<2, 1>{u}, dt, nullptr);
    const double along = -9.81 * std::sin(theta) * std::cos(yaw);  // uphill at yaw 0, downhill at pi, across at pi/2
    CHECK((a[state::kVx] - b[state::kVx]) / dt == Approx(along).margin(2e-3));
  }
}

TEST_CASE("the corrected model's ground bump drives like the surface plant's raised-cosine hill", "[surface][effects]") {
  // A 0.6 m hill of radius 10 m; the car starts 14 m away heading past its centre (off-centre by
  // 3 m, so the slope also pushes sideways) at 6 m/s and drives over it for 4 s.
  SurfaceLayer elevation;
  SurfacePatch hill;
  hill.centre_m = {14.0, 3.0};
  hill.radius_m = 10.0;
  hill.value = 0.6;
  elevation.patches.push_back(hill);
  const SingleTrackParams p;
  SurfaceLayer grip;
  grip.default_value = 1.0;
  const SingleTrackOnSurface plant(p, std::make_shared<const SurfaceMap>(grip, elevation));
  EffectParams e;
  e.bump_x_m = 14.0;
  e.bump_y_m = 3.0;
  e.bump_radius_m = 10.0;
  e.bump_height_m = 0.6;
  const CorrectedSingleTrack corrected{SingleTrack(p), e}, flat{SingleTrack(p)};
  VehicleState s;
  s.vx_mps = 6.f;
  float a[SingleTrack::kNx], b[CorrectedSingleTrack::kNx], c[CorrectedSingleTrack::kNx];
  plant.init_state(s, a);
  corrected.init_state(s, b);
  flat.init_state(s, c);
  const float u[2] = {0.02f, 0.25f};
  corrected.set_actuators(b, u[0], u[1]);
  flat.set_actuators(c, u[0], u[1]);
  std::vector<float> scratch(std::max<std::size_t>(1, corrected.scratch_floats(1)));
  double worst_vx = 0, worst_vy = 0, flat_vx = 0;
  for (int k = 0; k < 2000; ++k) {
    plant.step<1>(Batch<SingleTrack::kNx, 1>{a}, ConstBatch<2, 1>{u}, 0.002f, nullptr);
    corrected.step<1>(Batch<CorrectedSingleTrack::kNx, 1>{b}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
    flat.step<1>(Batch<CorrectedSingleTrack::kNx, 1>{c}, ConstBatch<2, 1>{u}, 0.002f, scratch.data());
    worst_vx = std::max(worst_vx, static_cast<double>(std::abs(a[state::kVx] - b[state::kVx])));
    worst_vy = std::max(worst_vy, static_cast<double>(std::abs(a[state::kVy] - b[state::kVy])));
    flat_vx = std::max(flat_vx, static_cast<double>(std::abs(a[state::kVx] - c[state::kVx])));
  }
  INFO("worst |dvx| " << worst_vx << " m/s, |dvy| " << worst_vy << " m/s; flat ground differs by " << flat_vx);
  CHECK(flat_vx > 0.3);                // the hill is felt: up to 9 % grade over 4 s
  CHECK(worst_vx < 0.02 * flat_vx);    // the two forms agree (sin vs tan of the slope: < 0.5 %)
  CHECK(worst_vy < 0.02);
}

TEST_CASE("surface plant: on a low-grip patch the tyre force is capped at mu_peak x scale x Fz, off it not", "[surface]") {
  SurfaceLayer grip;
  grip.default_value = 1.0;
  SurfacePatch patch;
  patch.centre_m = {0, 0};
  patch.radius_m = 3;
  patch.value = 0.4;
  grip.patches.push_back(patch);
  auto map = std::make_shared<const SurfaceMap>(grip, SurfaceLayer{});
  const SingleTrackParams p;
  const SingleTrackOnSurface car(p, map);
  const double mu_peak = p.tyre.D + p.tyre.Sv;  // sin(.) <= 1
  // Sliding hard sideways at 6 m/s: both tyres far beyond their peak slip.
  double x[SingleTrack::kNx] = {0, 0, 0, 6.0, 5.0, 0.5, 0, 6.0 / p.wheel_radius_m, 6.0 / p.wheel_radius_m};
  const double u[2] = {0.5, 0.0};
  const SingleTrackForces on = car.forces(x, u);
  for (const auto& [fx, fy, fz] : {std::tuple{on.front_fx_N, on.front_fy_N, on.front_fz_N},
                                  std::tuple{on.rear_fx_N, on.rear_fy_N, on.rear_fz_N}}) {
    CHECK(std::hypot(fx, fy) <= mu_peak * 0.4 * fz + 1e-9);
    CHECK(std::hypot(fx, fy) >= 0.75 * mu_peak * 0.4 * fz);  // sliding: near the cap
  }
  x[state::kX] = 10.0;  // the same slide off the patch: the full tyre
  const SingleTrackForces off = car.forces(x, u);
  CHECK(std::hypot(off.front_fx_N, off.front_fy_N) > mu_peak * 0.4 * off.front_fz_N * 2);
  CHECK(std::hypot(off.rear_fx_N, off.rear_fy_N) > mu_peak * 0.4 * off.rear_fz_N * 2);
  CHECK(std::hypot(off.rear_fx_N, off.rear_fy_N) <= mu_peak * off.rear_fz_N + 1e-9);
}

TEST_CASE("surface maps: the shipped examples load", "[surface]") {
  const SurfaceMap a = SurfaceMap::load(test::data_path("surfaces/gazebo_wet_patches.yaml"));
  CHECK(a.grip(-8.5, 10.2) == Approx(0.7));
  CHECK(a.elevation_m(-18.7, 0.0) == Approx(0.3));
  const SurfaceMap b = SurfaceMap::load(test::data_path("surfaces/gazebo_grip_image.yaml"));
  CHECK(b.grip(-15.0, 0.0) == Approx(1.0).margin(0.01));
  CHECK(b.grip(3.0, 0.0) == Approx(0.6).margin(0.01));
  CHECK(b.slope(0.0, 0.0).x == Approx(0.03));
}

TEST_CASE("closed loop on a surface map: drives, logs the surface, refuses plants without tyres to scale", "[surface]") {
  ClosedLoopConfig c;
  c.model = "single-track";
  c.plant = "single-track";
  c.surface_yaml = test::data_path("surfaces/gazebo_wet_patches.yaml");
  c.controller.num_samples = 64;
  c.controller.horizon = 30;
  c.controller.num_threads = 1;
  c.max_time_s = 3.0;
  c.laps = 1;
  c.progress = false;
  c.out_dir = (std::filesystem::temp_directory_path() / "mppi_surface_loop").string();
  const RunSummary s = run_closed_loop(c);
  CHECK(s.mean_speed_mps > 0.5);
  const Recording rec = RecordingReader::read(c.out_dir + "/log.csv");
  CHECK(rec.metadata.at("surface") == c.surface_yaml);
  for (const char* plant : {"kinematic", "double-track", "no-such-plant"}) {
    c.plant = plant;
    CHECK_THROWS_WITH(run_closed_loop(c), Catch::Contains("needs the single-track plant, not '" + std::string(plant)));
  }
}
