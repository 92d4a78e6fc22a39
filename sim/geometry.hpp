#pragma once
// Plane geometry for the track simulator: points, polylines (open or closed), closest points,
// distances between segments and to oriented rectangles, point-in-polygon, arc length and
// uniform resampling. Double precision: track lengths reach ~200 m and we want mm accuracy.
#include <cmath>
#include <cstddef>
#include <vector>

namespace mppi::sim {

struct Vec2 {
  double x = 0.0;
  double y = 0.0;
};
inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline double norm(Vec2 a) { return std::hypot(a.x, a.y); }
inline double distance(Vec2 a, Vec2 b) { return norm(a - b); }

// A sequence of vertices. Whether it is closed (last vertex joins the first) is passed to
// each function; a closed polyline does NOT repeat its first vertex at the end.
using Polyline = std::vector<Vec2>;

// Distance from p to segment [a, b]; *t_out (if given) = the parameter in [0, 1] of the
// closest point a + t (b - a). A degenerate segment (a == b) is a point.
double distance_to_segment(Vec2 p, Vec2 a, Vec2 b, double* t_out = nullptr);

// Smallest distance between segments [a, b] and [c, d] (0 if they intersect or touch).
double segment_distance(Vec2 a, Vec2 b, Vec2 c, Vec2 d);

// Number of segments: n - 1 if open, n if closed (for n >= 2; 0 otherwise).
std::size_t segment_count(const Polyline& line, bool closed);

// Cumulative arc length at each vertex: s[0] = 0, s[i] = length up to vertex i. A closed
// polyline gets one more entry, s[n] = the total length (back at vertex 0).
std::vector<double> cumulative_arc_length(const Polyline& line, bool closed);
double polyline_length(const Polyline& line, bool closed);

struct ClosestPoint {
  std::size_t segment = 0;  // segment i runs from vertex i to vertex i+1 (mod n when closed)
  double t = 0.0;           // position on that segment in [0, 1]
  Vec2 point;               // the closest point
  double distance_m = 0.0;  // |p - point|
};
// Closest point of the whole polyline (brute force; O(n)). Throws mppi::Error if the
// polyline has fewer than 2 vertices.
ClosestPoint closest_point(const Polyline& line, bool closed, Vec2 p);
// Same, searching only segments first_segment .. first_segment + count - 1 (indices wrap
// around on a closed polyline; clipped to the ends on an open one).
ClosestPoint closest_point_in_range(const Polyline& line, bool closed, Vec2 p,
                                    std::ptrdiff_t first_segment, std::size_t count);

// Shoelace area: positive when the vertices run counter-clockwise.
double signed_area(const Polyline& polygon);

// Even-odd rule (ray casting). Points exactly on an edge may go either way.
bool point_in_polygon(const Polyline& polygon, Vec2 p);

// Point at arc length s along the polyline (s wraps modulo the length if closed, is clamped
// to [0, length] if open). `cumulative` is cumulative_arc_length(line, closed).
Vec2 point_at_arc_length(const Polyline& line, bool closed, const std::vector<double>& cumulative,
                         double s);

// Vertices spaced uniformly in arc length, as close to spacing_m as divides the length.
// A closed result does not repeat its first vertex; an open one keeps both end points.
Polyline resample(const Polyline& line, bool closed, double spacing_m);

// Moving average over 2 * half_window + 1 vertices, repeated `passes` times (wraps around
// on a closed polyline; an open one keeps its end points).
Polyline smooth(const Polyline& line, bool closed, int half_window, int passes = 1);

// A rectangle of length x width, centred at `centre`, its length along heading yaw_rad.
struct OrientedRect {
  Vec2 centre;
  double yaw_rad = 0.0;
  double length_m = 0.0;
  double width_m = 0.0;
  // Corners in order front-left, rear-left, rear-right, front-right.
  void corners(Vec2 out[4]) const;
  bool contains(Vec2 p) const;
};
// Distance from the rectangle (solid) to segment [a, b]; 0 if they overlap.
double rect_segment_distance(const OrientedRect& rect, Vec2 a, Vec2 b);

// Axis-aligned bounds of a set of points.
struct Bounds {
  double x_min = 0.0, x_max = 0.0, y_min = 0.0, y_max = 0.0;
};
Bounds bounds_of(const Polyline& points);

}  // namespace mppi::sim
