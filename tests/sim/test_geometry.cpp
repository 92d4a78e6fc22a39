// Geometry helpers of the simulator against closed forms.
#include <catch2/catch.hpp>

#include <cmath>

#include "base/error.hpp"
#include "sim/geometry.hpp"

using namespace mppi::sim;

namespace {
constexpr double kPi = 3.14159265358979323846;

Polyline circle(double r, int n, Vec2 c = {}) {
  Polyline p;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n;
    p.push_back({c.x + r * std::cos(a), c.y + r * std::sin(a)});
  }
  return p;
}
const Polyline kSquare{{0, 0}, {4, 0}, {4, 4}, {0, 4}};  // CCW, side 4
}  // namespace

TEST_CASE("distance_to_segment matches hand-computed values", "[sim]") {
  double t = -1.0;
  CHECK(distance_to_segment({3, 4}, {0, 0}, {10, 0}, &t) == Approx(4.0));
  CHECK(t == Approx(0.3));
  CHECK(distance_to_segment({13, 4}, {0, 0}, {10, 0}, &t) == Approx(5.0));  // 3-4-5 past the end
  CHECK(t == Approx(1.0));
  CHECK(distance_to_segment({-3, -4}, {0, 0}, {10, 0}, &t) == Approx(5.0));
  CHECK(t == Approx(0.0));
  CHECK(distance_to_segment({1, 1}, {2, 2}, {2, 2}) == Approx(std::sqrt(2.0)));  // degenerate
  // Diagonal segment: distance from (2, 0) to the line y = x is sqrt(2).
  CHECK(distance_to_segment({2, 0}, {0, 0}, {5, 5}) == Approx(std::sqrt(2.0)));
}

TEST_CASE("segment_distance: parallel, crossing, touching and skew segments", "[sim]") {
  CHECK(segment_distance({0, 0}, {1, 0}, {0, 2}, {1, 2}) == Approx(2.0));
  CHECK(segment_distance({0, 0}, {2, 2}, {0, 2}, {2, 0}) == 0.0);
  CHECK(segment_distance({0, 0}, {1, 0}, {1, 0}, {1, 5}) == 0.0);  // touching end points
  CHECK(segment_distance({0, 0}, {1, 0}, {2, 1}, {3, 5}) == Approx(std::sqrt(2.0)));
  CHECK(segment_distance({0, 0}, {4, 0}, {2, 3}, {2, 1}) == Approx(1.0));  // T shape
}

TEST_CASE("arc length of a sampled circle is 2 pi r", "[sim]") {
  const double r = 3.0;
  const int n = 2000;
  const Polyline c = circle(r, n);
  // The inscribed polygon's perimeter exactly, and 2 pi r up to the chord error.
  CHECK(polyline_length(c, true) == Approx(2.0 * n * r * std::sin(kPi / n)).epsilon(1e-12));
  CHECK(polyline_length(c, true) == Approx(2.0 * kPi * r).epsilon(1e-6));
  // Open: one segment less.
  CHECK(polyline_length(c, false) == Approx(2.0 * (n - 1) * r * std::sin(kPi / n)).epsilon(1e-12));
  const auto s = cumulative_arc_length(c, true);
  REQUIRE(s.size() == c.size() + 1);
  CHECK(s[n / 4] == Approx(2.0 * (n / 4) * r * std::sin(kPi / n)));
}

TEST_CASE("signed area: shoelace sign and regular polygon area", "[sim]") {
  CHECK(signed_area(kSquare) == Approx(16.0));
  Polyline cw(kSquare.rbegin(), kSquare.rend());
  CHECK(signed_area(cw) == Approx(-16.0));
  const int n = 100;
  CHECK(signed_area(circle(2.0, n)) == Approx(0.5 * n * 4.0 * std::sin(2.0 * kPi / n)));
}

TEST_CASE("point_in_polygon on a square and a concave L", "[sim]") {
  CHECK(point_in_polygon(kSquare, {0.5, 0.5}));
  CHECK(point_in_polygon(kSquare, {3.9, 2.0}));
  CHECK_FALSE(point_in_polygon(kSquare, {4.1, 2.0}));
  CHECK_FALSE(point_in_polygon(kSquare, {-0.1, 2.0}));
  CHECK_FALSE(point_in_polygon(kSquare, {2.0, 4.5}));
  // Ray through a vertex (y = 4 row of the vertices) must not double count.
  CHECK_FALSE(point_in_polygon(kSquare, {-1.0, 4.0}));
  const Polyline ell{{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 4}, {0, 4}};
  CHECK(point_in_polygon(ell, {0.5, 3.0}));
  CHECK(point_in_polygon(ell, {3.0, 0.5}));
  CHECK_FALSE(point_in_polygon(ell, {3.0, 3.0}));  // the notch
}

TEST_CASE("closest point on polylines", "[sim]") {
  const ClosestPoint c = closest_point(kSquare, true, {5.0, 1.0});
  CHECK(c.segment == 1);  // (4,0) -> (4,4)
  CHECK(c.t == Approx(0.25));
  CHECK(c.point.x == Approx(4.0));
  CHECK(c.point.y == Approx(1.0));
  CHECK(c.distance_m == Approx(1.0));
  // The closing segment (0,4) -> (0,0) counts only when closed.
  const ClosestPoint closed = closest_point(kSquare, true, {-1.0, 2.0});
  CHECK(closed.segment == 3);
  CHECK(closed.distance_m == Approx(1.0));
  const ClosestPoint open = closest_point(kSquare, false, {-1.0, 2.0});
  CHECK(open.distance_m == Approx(std::sqrt(5.0)));  // to the vertex (0,4) or (0,0)
  // A range that wraps around the end of a closed polyline.
  const ClosestPoint wrapped = closest_point_in_range(kSquare, true, {-1.0, 2.0}, -1, 2);
  CHECK(wrapped.segment == 3);
  // Circle: distance from a point at radius 5 to the radius-3 polygon is ~2.
  CHECK(closest_point(circle(3.0, 720), true, {0.0, 5.0}).distance_m == Approx(2.0).margin(1e-4));
  CHECK_THROWS_AS(closest_point(Polyline{{0, 0}}, true, {1, 1}), mppi::Error);
}

TEST_CASE("point_at_arc_length walks the square and wraps", "[sim]") {
  const auto s = cumulative_arc_length(kSquare, true);
  const Vec2 a = point_at_arc_length(kSquare, true, s, 5.0);
  CHECK(a.x == Approx(4.0));
  CHECK(a.y == Approx(1.0));
  const Vec2 b = point_at_arc_length(kSquare, true, s, 17.0);  // 16 + 1
  CHECK(b.x == Approx(1.0));
  CHECK(b.y == Approx(0.0).margin(1e-12));
  const Vec2 c = point_at_arc_length(kSquare, true, s, -1.0);  // on the closing segment
  CHECK(c.x == Approx(0.0).margin(1e-12));
  CHECK(c.y == Approx(1.0));
}

TEST_CASE("resample gives uniform spacing on the original outline", "[sim]") {
  const Polyline r = resample(kSquare, true, 0.5);
  REQUIRE(r.size() == 32);  // perimeter 16 / 0.5
  for (std::size_t i = 0; i < r.size(); ++i) {
    CHECK(distance(r[i], r[(i + 1) % r.size()]) == Approx(0.5));
    CHECK(closest_point(kSquare, true, r[i]).distance_m == Approx(0.0).margin(1e-12));
  }
  const Polyline open = resample(Polyline{{0, 0}, {3, 0}}, false, 1.0);
  REQUIRE(open.size() == 4);
  CHECK(open.back().x == 3.0);
}

TEST_CASE("smooth: collinear points stay, a regular polygon shrinks by the closed form", "[sim]") {
  Polyline line;
  for (int i = 0; i < 10; ++i) line.push_back({0.5 * i, 1.0 + 0.25 * i});
  const Polyline s = smooth(line, false, 2, 3);
  for (std::size_t i = 0; i < line.size(); ++i) {
    CHECK(s[i].x == Approx(line[i].x));
    CHECK(s[i].y == Approx(line[i].y));
  }
  // 3-point average of a regular n-gon of radius r: radius r (1 + 2 cos(2 pi / n)) / 3.
  const int n = 12;
  const double r = 2.0;
  const Polyline sm = smooth(circle(r, n), true, 1, 1);
  const double expected = r * (1.0 + 2.0 * std::cos(2.0 * kPi / n)) / 3.0;
  for (const Vec2& p : sm) CHECK(norm(p) == Approx(expected));
}

TEST_CASE("oriented rectangle corners and distance to segments", "[sim]") {
  OrientedRect rect{{1.0, 2.0}, kPi / 2.0, 2.0, 1.0};  // pointing +y: spans x 0.5..1.5, y 1..3
  Vec2 c[4];
  rect.corners(c);
  CHECK(c[0].x == Approx(0.5));  // front-left
  CHECK(c[0].y == Approx(3.0));
  CHECK(c[2].x == Approx(1.5));  // rear-right
  CHECK(c[2].y == Approx(1.0));
  CHECK(rect.contains({1.4, 2.9}));
  CHECK_FALSE(rect.contains({1.6, 2.0}));
  CHECK(rect_segment_distance(rect, {4.0, -5.0}, {4.0, 5.0}) == Approx(2.5));
  CHECK(rect_segment_distance(rect, {0.0, 2.0}, {2.0, 2.0}) == 0.0);    // crosses
  CHECK(rect_segment_distance(rect, {1.0, 2.0}, {1.1, 2.1}) == 0.0);    // inside
  CHECK(rect_segment_distance(rect, {2.5, 4.0}, {3.0, 6.0}) == Approx(std::sqrt(2.0)));  // corner
}
