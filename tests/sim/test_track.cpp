// Built-in tracks against the geometry documented in data/autorally (README, numpy).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

#include "base/error.hpp"
#include "sim/data_dir.hpp"
#include "sim/track.hpp"
#include "test_data.hpp"

using namespace mppi::sim;
using Catch::Matchers::Contains;

namespace {
constexpr double kPi = 3.14159265358979323846;

TrackOptions test_options() {
  TrackOptions o;
  o.data_dir = mppi::test::data_path("");
  return o;
}

const Track& gazebo() {
  static const Track t = Track::load("gazebo", test_options());
  return t;
}

// README: p_mppi = Rot(135 deg) p_mesh + (-8.5, 0). In the mesh frame the oval's straights are
// at y = +-4.476 (inner pipe) and +-7.83 (outer pipe) for |x| <= 5.81.
Vec2 to_mesh(Vec2 p) {
  const double a = -135.0 * kPi / 180.0;
  const Vec2 d{p.x + 8.5, p.y};
  return {std::cos(a) * d.x - std::sin(a) * d.y, std::sin(a) * d.x + std::cos(a) * d.y};
}
}  // namespace

TEST_CASE("Track::load rejects an unknown name and lists the valid ones", "[sim]") {
  CHECK_THROWS_WITH(Track::load("monza", test_options()),
                    Contains("monza") && Contains("gazebo") && Contains("marietta") &&
                        Contains("ccrf"));
}

TEST_CASE("gazebo: barriers are the pipe rings of the README", "[sim]") {
  const Track& t = gazebo();
  REQUIRE(t.has_barriers());
  REQUIRE(t.barriers().size() == 2);
  for (const Barrier& b : t.barriers()) CHECK(b.radius_m == Approx(0.077));
  // README: 51.1 m and 72.2 m around.
  CHECK(polyline_length(t.barriers()[0].centre, true) == Approx(51.1).margin(0.05));
  CHECK(polyline_length(t.barriers()[1].centre, true) == Approx(72.2).margin(0.05));
  CHECK(t.costmap_path().find("gazebo/gazebo_costmap.npz") != std::string::npos);
}

TEST_CASE("gazebo: centreline between the rings, 1.6 m from each pipe on the straights", "[sim]") {
  const Track& t = gazebo();
  CHECK(t.length_m() > 51.1);
  CHECK(t.length_m() < 72.2);
  // Uniform spacing ~0.25 m.
  const auto& s = t.centreline_arc_m();
  for (std::size_t i = 0; i + 1 < s.size(); ++i) CHECK(s[i + 1] - s[i] == Approx(0.25).margin(0.01));
  // Straights: midway between y = 4.476 and 7.83 (6.153), i.e. (7.83 - 4.476) / 2 - 0.077 = 1.60 m
  // from each pipe's surface (README: ~3.18 m clear between the pipes).
  int on_straights = 0;
  for (const Vec2& p : t.centreline()) {
    const Vec2 m = to_mesh(p);
    if (std::abs(m.x) > 5.0) continue;
    ++on_straights;
    CHECK(std::abs(m.y) == Approx((4.4756 + 7.8294) / 2.0).margin(0.02));
    for (const Barrier& b : t.barriers())
      CHECK(closest_point(b.centre, true, p).distance_m - b.radius_m ==
            Approx((7.8294 - 4.4756) / 2.0 - 0.077).margin(0.02));
  }
  CHECK(on_straights > 60);  // two 10 m stretches at 0.25 m
}

TEST_CASE("gazebo: start pose on a straight, heading counter-clockwise", "[sim]") {
  const Track& t = gazebo();
  const Pose2 s = t.start_pose();
  CHECK(s.x_m == t.centreline()[0].x);
  CHECK(s.y_m == t.centreline()[0].y);
  CHECK(std::abs(to_mesh({s.x_m, s.y_m}).x) < 3.0);  // near the middle of a straight
  // CCW around the oval's centre (-8.5, 0): (p - c) x heading > 0.
  const Vec2 r{s.x_m + 8.5, s.y_m};
  CHECK(cross(r, {std::cos(s.yaw_rad), std::sin(s.yaw_rad)}) > 0.0);
  CHECK(signed_area(t.centreline()) > 0.0);

  TrackOptions cw = test_options();
  cw.direction = Direction::kClockwise;
  const Track t_cw = Track::load("gazebo", cw);
  CHECK(signed_area(t_cw.centreline()) < 0.0);
  CHECK(t_cw.start_pose().x_m == Approx(s.x_m));
  CHECK(t_cw.start_pose().y_m == Approx(s.y_m));
  CHECK(std::cos(t_cw.start_pose().yaw_rad - s.yaw_rad) == Approx(-1.0).margin(1e-6));
  CHECK(t_cw.length_m() == Approx(t.length_m()));
}

TEST_CASE("marietta and ccrf: closed boundaries, inner inside outer, centreline on track", "[sim]") {
  struct Case {
    const char* name;
    double inner_m, outer_m;  // loop lengths (numpy on the closed survey loops)
  };
  // ccrf: README says 174.5 m and 197.8 m around.
  for (const Case& c : {Case{"marietta", 55.13, 70.77}, Case{"ccrf", 174.5, 197.8}}) {
    INFO(c.name);
    const Track t = Track::load(c.name, test_options());
    CHECK_FALSE(t.has_barriers());
    CHECK(signed_area(t.inner()) > 0.0);
    CHECK(signed_area(t.outer()) > signed_area(t.inner()));
    CHECK(polyline_length(t.inner(), true) == Approx(c.inner_m).epsilon(0.01));
    CHECK(polyline_length(t.outer(), true) == Approx(c.outer_m).epsilon(0.01));
    // Downsampled from 5 mm to ~5 cm.
    CHECK(polyline_length(t.outer(), true) / static_cast<double>(t.outer().size()) ==
          Approx(0.05).margin(0.005));
    CHECK(t.length_m() > polyline_length(t.inner(), true));
    CHECK(t.length_m() < polyline_length(t.outer(), true));
    for (const Vec2& p : t.centreline()) {
      CHECK(t.is_on_track(p));
      // Centred: the two boundary distances agree to well under the 2.5-4.4 m track width.
      const double di = closest_point(t.inner(), true, p).distance_m;
      const double dout = closest_point(t.outer(), true, p).distance_m;
      CHECK(std::abs(di - dout) < 0.25);
    }
    CHECK(t.is_on_track({t.start_pose().x_m, t.start_pose().y_m}));
  }
}

TEST_CASE("close_loop trims the overlapping end of a survey", "[sim]") {
  // 1.1 turns of a radius-5 circle starting on a short hook: keeps exactly one turn.
  Polyline raw;
  for (int i = 0; i < 20; ++i) raw.push_back({5.0 + 0.05 * (20 - i), 0.0});  // hook
  for (int i = 0; i <= 1100; ++i) {
    const double a = 2.0 * kPi * i / 1000.0;
    raw.push_back({5.0 * std::cos(a), 5.0 * std::sin(a)});
  }
  const Polyline loop = close_loop(raw, 1.0, "test");
  CHECK(polyline_length(loop, true) == Approx(2.0 * kPi * 5.0).epsilon(1e-3));
  Polyline open(raw.begin() + 20, raw.begin() + 700);  // 0.68 of a turn: does not close
  CHECK_THROWS_WITH(close_loop(open, 1.0, "survey.npz"), Contains("survey.npz") && Contains("close"));
}

TEST_CASE("from_boundaries swaps inner and outer given the other way round", "[sim]") {
  Polyline small, big;
  for (int i = 0; i < 200; ++i) {
    const double a = 2.0 * kPi * i / 200.0;
    small.push_back({9.0 * std::cos(a), 9.0 * std::sin(a)});
    big.push_back({11.0 * std::cos(-a), 11.0 * std::sin(-a)});  // clockwise
  }
  const Track t = Track::from_boundaries("ring", big, small, {}, "", {});
  CHECK(signed_area(t.inner()) == Approx(signed_area(small)));
  CHECK(signed_area(t.outer()) == Approx(-signed_area(big)));
  for (const Vec2& p : t.centreline()) CHECK(norm(p) == Approx(10.0).margin(0.01));
  CHECK(t.length_m() == Approx(2.0 * kPi * 10.0).epsilon(2e-3));
}

TEST_CASE("data_dir honours MPPI_DATA_DIR and explains a wrong folder", "[sim]") {
  const char* old = std::getenv("MPPI_DATA_DIR");
  const std::string saved = old ? old : "";
  ::setenv("MPPI_DATA_DIR", "/nonexistent-mppi-data", 1);
  CHECK_THROWS_WITH(data_dir(), Contains("/nonexistent-mppi-data") && Contains("autorally"));
  const std::string good = mppi::test::data_path("");
  ::setenv("MPPI_DATA_DIR", good.c_str(), 1);
  CHECK(data_dir() == good);
  CHECK(data_file("autorally/maps/gazebo/gazebo_costmap.npz") ==
        good + "/autorally/maps/gazebo/gazebo_costmap.npz");
  CHECK_THROWS_WITH(data_file("autorally/nope.npz"), Contains("nope.npz"));
  if (old)
    ::setenv("MPPI_DATA_DIR", saved.c_str(), 1);
  else
    ::unsetenv("MPPI_DATA_DIR");
}
