#include "sim/track.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.hpp"
#include "base/npz.hpp"
#include "sim/data_dir.hpp"

namespace mppi::sim {

namespace {


std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// Two 1-D arrays of equal length -> polyline.
Polyline polyline_from_xy(const NpzFile& npz, const std::string& kx, const std::string& ky) {
  const NpyArray& x = npz.at(kx);
  const NpyArray& y = npz.at(ky);
  if (x.shape.size() != 1 || y.shape.size() != 1 || x.size() != y.size())
    throw Error(npz.path() + ": arrays '" + kx + "' and '" + ky +
                "' must be 1-D and of equal length");
  Polyline p(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) p[i] = {x.values[i], y.values[i]};
  return p;
}

// An (N, 2) array -> polyline.
Polyline polyline_from_n2(const NpzFile& npz, const std::string& key) {
  const NpyArray& a = npz.at(key);
  if (a.shape.size() != 2 || a.shape[1] != 2 || a.shape[0] < 3)
    throw Error(npz.path() + ": array '" + key + "' must have shape (N, 2) with N >= 3");
  Polyline p(a.shape[0]);
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = {a.values[2 * i], a.values[2 * i + 1]};
  return p;
}

Polyline counter_clockwise(Polyline p) {
  if (signed_area(p) < 0.0) std::reverse(p.begin(), p.end());
  return p;
}

// Index of the vertex in the middle of the straightest stretch: the window sums of the turning
// angle over +-half_window_m are computed for every vertex; among the vertices within 0.02 rad
// of the smallest sum, the longest consecutive run wins (the first one found on a tie), and its
// middle vertex is returned. Runs make the choice stable where two straights tie.
std::size_t straightest_vertex(const Polyline& line, double spacing_m, double half_window_m) {
  const std::size_t n = line.size();
  std::vector<double> turn(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = line[(i + n - 1) % n], b = line[i], c = line[(i + 1) % n];
    turn[i] = std::abs(std::atan2(cross(b - a, c - b), dot(b - a, c - b)));
  }
  const auto w = static_cast<std::ptrdiff_t>(
      std::min<double>(std::lround(half_window_m / spacing_m), static_cast<double>(n / 4)));
  const auto sn = static_cast<std::ptrdiff_t>(n);
  std::vector<double> sum(n, 0.0);
  for (std::ptrdiff_t i = 0; i < sn; ++i)
    for (std::ptrdiff_t k = -w; k <= w; ++k)
      sum[static_cast<std::size_t>(i)] += turn[static_cast<std::size_t>(((i + k) % sn + sn) % sn)];
  const double limit = *std::min_element(sum.begin(), sum.end()) + 0.02;
  // Start scanning just after a vertex outside the limit so no run is split.
  std::size_t first = n;
  for (std::size_t i = 0; i < n; ++i)
    if (sum[i] > limit) {
      first = i;
      break;
    }
  if (first == n) return 0;  // equally curved everywhere (a circle)
  std::size_t best_start = 0, best_len = 0, run_start = 0, run_len = 0;
  for (std::size_t k = 1; k <= n; ++k) {
    const std::size_t i = (first + k) % n;
    if (sum[i] <= limit) {
      if (run_len == 0) run_start = i;
      if (++run_len > best_len) best_len = run_len, best_start = run_start;
    } else {
      run_len = 0;
    }
  }
  return (best_start + best_len / 2) % n;
}

}  // namespace

Polyline close_loop(const Polyline& raw, double max_gap_m, const std::string& what) {
  const std::size_t n = raw.size();
  if (n < 8) throw Error(what + ": boundary needs at least 8 points, has " + std::to_string(n));
  // Gap A: end point against the first quarter; gap B: start point against the last quarter.
  double gap_a = std::numeric_limits<double>::infinity(), gap_b = gap_a;
  std::size_t j_a = 0, i_b = n - 1;
  for (std::size_t j = 0; j < n / 4; ++j) {
    const double d = distance(raw[n - 1], raw[j]);
    if (d < gap_a) gap_a = d, j_a = j;
  }
  for (std::size_t i = n - n / 4; i < n; ++i) {
    const double d = distance(raw[0], raw[i]);
    if (d < gap_b) gap_b = d, i_b = i;
  }
  if (std::min(gap_a, gap_b) > max_gap_m)
    throw Error(what + ": boundary does not close (ends " + std::to_string(std::min(gap_a, gap_b)) +
                " m apart, limit " + std::to_string(max_gap_m) + " m)");
  if (gap_a <= gap_b) return Polyline(raw.begin() + static_cast<std::ptrdiff_t>(j_a), raw.end() - 1);
  return Polyline(raw.begin(), raw.begin() + static_cast<std::ptrdiff_t>(i_b));
}

Polyline centreline_between(const Polyline& inner, const Polyline& outer, double spacing_m) {
  const Polyline in = resample(inner, true, 0.05);
  const Polyline out = resample(outer, true, 0.05);
  Polyline mids(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    Vec2 q;
    for (const Vec2& o : out) {
      const Vec2 d = o - in[i];
      const double d2 = dot(d, d);
      if (d2 < best) best = d2, q = o;
    }
    mids[i] = 0.5 * (in[i] + q);
  }
  // Moving average over +-0.5 m: removes the kinks where the nearest outer point jumps.
  // (It pulls a curve of radius R inwards by about spacing^2 / R: 1 cm at R = 6 m.)
  Polyline centre = resample(mids, true, spacing_m);
  const int half = std::max(1, static_cast<int>(std::lround(0.5 / spacing_m)));
  centre = smooth(centre, true, half, 1);
  // Around a hairpin the nearest-point midpoints cut the corner; re-centre each vertex along
  // its normal until it is as far from one boundary as from the other (the medial line).
  const bool inner_ccw = signed_area(inner) > 0.0;
  for (int iteration = 0; iteration < 3; ++iteration) {
    centre = resample(centre, true, spacing_m);
    const std::size_t n = centre.size();
    Polyline moved(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 tangent = centre[(i + 1) % n] - centre[(i + n - 1) % n];
      const double len = norm(tangent);
      // Left normal; the inner boundary lies to the left when both run counter-clockwise.
      Vec2 to_inner = len > 0.0 ? Vec2{-tangent.y / len, tangent.x / len} : Vec2{};
      if (!inner_ccw) to_inner = -1.0 * to_inner;
      const double d_in = closest_point(inner, true, centre[i]).distance_m;
      const double d_out = closest_point(outer, true, centre[i]).distance_m;
      moved[i] = centre[i] + (0.5 * (d_in - d_out)) * to_inner;
    }
    centre = smooth(moved, true, half, 1);
  }
  return resample(centre, true, spacing_m);
}

std::vector<std::string> Track::names() { return {"gazebo", "marietta", "ccrf"}; }

Track Track::load(const std::string& name, const TrackOptions& options) {
  const std::string root = options.data_dir.empty() ? data_dir() : options.data_dir;
  const std::string maps = root + "/autorally/maps/";
  const double spacing = options.boundary_spacing_m;
  if (name == "gazebo") {
    const NpzFile npz = NpzFile::load(maps + "gazebo/gazebo_track_barriers.npz");
    const double radius = npz.at("tube_radius", {1}).values[0];
    if (!(radius > 0.0)) throw Error(npz.path() + ": array 'tube_radius' must be > 0");
    Polyline inner = polyline_from_n2(npz, "inner_mppi");
    Polyline outer = polyline_from_n2(npz, "outer_mppi");
    std::vector<Barrier> barriers{{"inner barrier", inner, radius}, {"outer barrier", outer, radius}};
    return from_boundaries(name, std::move(inner), std::move(outer), std::move(barriers),
                           maps + "gazebo/gazebo_costmap.npz", options);
  }
  if (name == "marietta" || name == "ccrf") {
    const bool ma = name == "marietta";
    const NpzFile npz = NpzFile::load(maps + name + "/track_boundaries.npz");
    const Polyline raw_in = ma ? polyline_from_xy(npz, "arr_0", "arr_1") : polyline_from_xy(npz, "X_in", "Y_in");
    const Polyline raw_out = ma ? polyline_from_xy(npz, "arr_2", "arr_3") : polyline_from_xy(npz, "X_out", "Y_out");
    Polyline inner = resample(close_loop(raw_in, 1.0, npz.path() + " (inner boundary)"), true, spacing);
    Polyline outer = resample(close_loop(raw_out, 1.0, npz.path() + " (outer boundary)"), true, spacing);
    const std::string costmap = maps + name + (ma ? "/marietta_costmap_2017.npz" : "/ccrf_costmap_2017.npz");
    return from_boundaries(name, std::move(inner), std::move(outer), {}, costmap, options);
  }
  throw Error("unknown track '" + name + "' (valid: " + join(names()) + ")");
}

Track Track::from_boundaries(std::string name, Polyline inner, Polyline outer,
                             std::vector<Barrier> barriers, std::string costmap_path,
                             const TrackOptions& options) {
  if (inner.size() < 3 || outer.size() < 3)
    throw Error("track '" + name + "': boundaries need at least 3 vertices");
  if (!(options.centreline_spacing_m > 0.0))
    throw Error("track '" + name + "': centreline spacing must be > 0 m");
  inner = counter_clockwise(std::move(inner));
  outer = counter_clockwise(std::move(outer));
  if (signed_area(inner) > signed_area(outer)) std::swap(inner, outer);  // files named the other way
  for (const Vec2& p : inner)
    if (!point_in_polygon(outer, p))
      throw Error("track '" + name + "': inner boundary is not inside the outer boundary (vertex " +
                  std::to_string(p.x) + ", " + std::to_string(p.y) + ")");

  Track t;
  t.name_ = std::move(name);
  t.costmap_path_ = std::move(costmap_path);
  t.direction_ = options.direction;
  t.inner_ = std::move(inner);
  t.outer_ = std::move(outer);
  t.barriers_ = std::move(barriers);

  Polyline centre = centreline_between(t.inner_, t.outer_, options.centreline_spacing_m);
  const std::size_t start = straightest_vertex(centre, options.centreline_spacing_m, 5.0);
  std::rotate(centre.begin(), centre.begin() + static_cast<std::ptrdiff_t>(start), centre.end());
  if (options.direction == Direction::kClockwise) std::reverse(centre.begin() + 1, centre.end());
  t.centreline_ = std::move(centre);
  t.centreline_arc_m_ = cumulative_arc_length(t.centreline_, true);

  const std::size_t n = t.centreline_.size();
  const Vec2 heading = t.centreline_[1] - t.centreline_[n - 1];
  t.start_ = {t.centreline_[0].x, t.centreline_[0].y, std::atan2(heading.y, heading.x)};
  return t;
}

bool Track::is_on_track(Vec2 p) const {
  return point_in_polygon(outer_, p) && !point_in_polygon(inner_, p);
}

Bounds Track::bounds() const {
  Bounds b = bounds_of(outer_);
  const Bounds bi = bounds_of(inner_);
  b = {std::min(b.x_min, bi.x_min), std::max(b.x_max, bi.x_max), std::min(b.y_min, bi.y_min),
       std::max(b.y_max, bi.y_max)};
  for (const Barrier& bar : barriers_) {
    const Bounds bb = bounds_of(bar.centre);
    b = {std::min(b.x_min, bb.x_min - bar.radius_m), std::max(b.x_max, bb.x_max + bar.radius_m),
         std::min(b.y_min, bb.y_min - bar.radius_m), std::max(b.y_max, bb.y_max + bar.radius_m)};
  }
  return b;
}

}  // namespace mppi::sim
