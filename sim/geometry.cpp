#include "sim/geometry.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "base/error.hpp"

namespace mppi::sim {

double distance_to_segment(Vec2 p, Vec2 a, Vec2 b, double* t_out) {
  const Vec2 ab = b - a;
  const double len2 = dot(ab, ab);
  double t = 0.0;
  if (len2 > 0.0) t = std::clamp(dot(p - a, ab) / len2, 0.0, 1.0);
  if (t_out) *t_out = t;
  return distance(p, a + t * ab);
}

namespace {
// Sign of the turn a -> b -> c: +1 left, -1 right, 0 collinear.
int orientation(Vec2 a, Vec2 b, Vec2 c) {
  const double v = cross(b - a, c - a);
  return (v > 0.0) - (v < 0.0);
}
bool on_segment_if_collinear(Vec2 a, Vec2 b, Vec2 p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}
bool segments_intersect(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const int o1 = orientation(a, b, c), o2 = orientation(a, b, d);
  const int o3 = orientation(c, d, a), o4 = orientation(c, d, b);
  if (o1 != o2 && o3 != o4) return true;
  return (o1 == 0 && on_segment_if_collinear(a, b, c)) ||
         (o2 == 0 && on_segment_if_collinear(a, b, d)) ||
         (o3 == 0 && on_segment_if_collinear(c, d, a)) ||
         (o4 == 0 && on_segment_if_collinear(c, d, b));
}
void require_vertices(const Polyline& line, const char* where) {
  if (line.size() < 2)
    throw Error(std::string(where) + ": polyline needs at least 2 vertices, has " +
                std::to_string(line.size()));
}
}  // namespace

double segment_distance(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  if (segments_intersect(a, b, c, d)) return 0.0;
  return std::min({distance_to_segment(a, c, d), distance_to_segment(b, c, d),
                   distance_to_segment(c, a, b), distance_to_segment(d, a, b)});
}

std::size_t segment_count(const Polyline& line, bool closed) {
  if (line.size() < 2) return 0;
  return closed ? line.size() : line.size() - 1;
}

std::vector<double> cumulative_arc_length(const Polyline& line, bool closed) {
  std::vector<double> s;
  if (line.empty()) return s;
  const std::size_t n = line.size();
  s.resize(closed ? n + 1 : n);
  s[0] = 0.0;
  for (std::size_t i = 1; i < s.size(); ++i) s[i] = s[i - 1] + distance(line[i - 1], line[i % n]);
  return s;
}

double polyline_length(const Polyline& line, bool closed) {
  const auto s = cumulative_arc_length(line, closed);
  return s.empty() ? 0.0 : s.back();
}

ClosestPoint closest_point_in_range(const Polyline& line, bool closed, Vec2 p,
                                    std::ptrdiff_t first_segment, std::size_t count) {
  require_vertices(line, "closest_point");
  const auto n = static_cast<std::ptrdiff_t>(line.size());
  const auto segments = static_cast<std::ptrdiff_t>(segment_count(line, closed));
  std::ptrdiff_t begin = first_segment;
  std::ptrdiff_t end = first_segment + static_cast<std::ptrdiff_t>(std::min<std::size_t>(
                                           count, static_cast<std::size_t>(segments)));
  if (!closed) {
    begin = std::clamp<std::ptrdiff_t>(begin, 0, segments);
    end = std::clamp<std::ptrdiff_t>(end, begin, segments);
  }
  ClosestPoint best;
  best.distance_m = std::numeric_limits<double>::infinity();
  for (std::ptrdiff_t k = begin; k < end; ++k) {
    const std::ptrdiff_t i = ((k % segments) + segments) % segments;
    const Vec2 a = line[static_cast<std::size_t>(i)];
    const Vec2 b = line[static_cast<std::size_t>((i + 1) % n)];
    double t = 0.0;
    const double d = distance_to_segment(p, a, b, &t);
    if (d < best.distance_m) {
      best.distance_m = d;
      best.segment = static_cast<std::size_t>(i);
      best.t = t;
      best.point = a + t * (b - a);
    }
  }
  return best;
}

ClosestPoint closest_point(const Polyline& line, bool closed, Vec2 p) {
  return closest_point_in_range(line, closed, p, 0, segment_count(line, closed));
}

double signed_area(const Polyline& polygon) {
  double twice = 0.0;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0; i < n; ++i) twice += cross(polygon[i], polygon[(i + 1) % n]);
  return 0.5 * twice;
}

bool point_in_polygon(const Polyline& polygon, Vec2 p) {
  bool inside = false;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec2 a = polygon[i], b = polygon[j];
    // Half-open rule on y so a vertex on the ray is counted once.
    if ((a.y > p.y) != (b.y > p.y)) {
      const double x_cross = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
      if (p.x < x_cross) inside = !inside;
    }
  }
  return inside;
}

Vec2 point_at_arc_length(const Polyline& line, bool closed, const std::vector<double>& cumulative,
                         double s) {
  require_vertices(line, "point_at_arc_length");
  const double total = cumulative.back();
  if (closed) {
    s = std::fmod(s, total);
    if (s < 0.0) s += total;
  } else {
    s = std::clamp(s, 0.0, total);
  }
  // First vertex with cumulative > s; the point lies on the segment before it.
  auto it = std::upper_bound(cumulative.begin(), cumulative.end(), s);
  std::size_t k = static_cast<std::size_t>(it - cumulative.begin());
  if (k == 0) k = 1;
  if (k >= cumulative.size()) k = cumulative.size() - 1;
  const Vec2 a = line[k - 1];
  const Vec2 b = line[k % line.size()];
  const double seg = cumulative[k] - cumulative[k - 1];
  const double t = seg > 0.0 ? (s - cumulative[k - 1]) / seg : 0.0;
  return a + t * (b - a);
}

Polyline resample(const Polyline& line, bool closed, double spacing_m) {
  require_vertices(line, "resample");
  if (!(spacing_m > 0.0)) throw Error("resample: spacing must be > 0 m");
  const auto cum = cumulative_arc_length(line, closed);
  const double total = cum.back();
  if (!(total > 0.0)) throw Error("resample: polyline has zero length");
  const auto intervals = std::max<std::size_t>(closed ? 3 : 1,
                                               static_cast<std::size_t>(std::lround(total / spacing_m)));
  const double step = total / static_cast<double>(intervals);
  Polyline out;
  const std::size_t count = closed ? intervals : intervals + 1;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i)
    out.push_back(point_at_arc_length(line, closed, cum, step * static_cast<double>(i)));
  if (!closed) out.back() = line.back();  // exact end point despite rounding
  return out;
}

Polyline smooth(const Polyline& line, bool closed, int half_window, int passes) {
  if (half_window <= 0 || passes <= 0 || line.size() < 3) return line;
  const auto n = static_cast<std::ptrdiff_t>(line.size());
  Polyline cur = line, next(line.size());
  for (int pass = 0; pass < passes; ++pass) {
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      if (!closed && (i == 0 || i == n - 1)) {
        next[static_cast<std::size_t>(i)] = cur[static_cast<std::size_t>(i)];
        continue;
      }
      // Open polylines shrink the window near the ends so it stays symmetric.
      std::ptrdiff_t h = half_window;
      if (!closed) h = std::min({h, i, n - 1 - i});
      Vec2 sum;
      for (std::ptrdiff_t k = -h; k <= h; ++k)
        sum = sum + cur[static_cast<std::size_t>(((i + k) % n + n) % n)];
      next[static_cast<std::size_t>(i)] = (1.0 / static_cast<double>(2 * h + 1)) * sum;
    }
    std::swap(cur, next);
  }
  return cur;
}

void OrientedRect::corners(Vec2 out[4]) const {
  const Vec2 f{std::cos(yaw_rad) * 0.5 * length_m, std::sin(yaw_rad) * 0.5 * length_m};
  const Vec2 l{-std::sin(yaw_rad) * 0.5 * width_m, std::cos(yaw_rad) * 0.5 * width_m};
  out[0] = centre + f + l;
  out[1] = centre - f + l;
  out[2] = centre - f - l;
  out[3] = centre + f - l;
}

bool OrientedRect::contains(Vec2 p) const {
  const Vec2 d = p - centre;
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const double along = c * d.x + s * d.y;
  const double across = -s * d.x + c * d.y;
  return std::abs(along) <= 0.5 * length_m && std::abs(across) <= 0.5 * width_m;
}

double rect_segment_distance(const OrientedRect& rect, Vec2 a, Vec2 b) {
  if (rect.contains(a) || rect.contains(b)) return 0.0;
  Vec2 c[4];
  rect.corners(c);
  double d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) d = std::min(d, segment_distance(a, b, c[i], c[(i + 1) % 4]));
  return d;
}

Bounds bounds_of(const Polyline& points) {
  Bounds b;
  if (points.empty()) return b;
  b.x_min = b.x_max = points[0].x;
  b.y_min = b.y_max = points[0].y;
  for (const Vec2& p : points) {
    b.x_min = std::min(b.x_min, p.x);
    b.x_max = std::max(b.x_max, p.x);
    b.y_min = std::min(b.y_min, p.y);
    b.y_max = std::max(b.y_max, p.y);
  }
  return b;
}

}  // namespace mppi::sim
