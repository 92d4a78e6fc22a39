#include "sim/crash_detector.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "base/error.hpp"

namespace mppi::sim {

namespace {
const char* const kCornerNames[4] = {"front-left", "rear-left", "rear-right", "front-right"};

std::string at_point(Vec2 p) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%.2f, %.2f)", p.x, p.y);
  return buf;
}
}  // namespace

CrashDetector::BandedPolygon::BandedPolygon(const Polyline& polygon, double band_height_m)
    : band_m_(band_height_m) {
  const Bounds b = bounds_of(polygon);
  y0_ = b.y_min;
  const auto count = static_cast<std::size_t>(std::floor((b.y_max - b.y_min) / band_m_)) + 1;
  bands_.resize(count);
  const std::size_t n = polygon.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = polygon[i], c = polygon[(i + 1) % n];
    if (a.y == c.y) continue;  // a horizontal edge never crosses a horizontal ray
    const auto k0 = static_cast<std::size_t>(std::floor((std::min(a.y, c.y) - y0_) / band_m_));
    const auto k1 = std::min(count - 1, static_cast<std::size_t>(
                                            std::floor((std::max(a.y, c.y) - y0_) / band_m_)));
    for (std::size_t k = k0; k <= k1; ++k) bands_[k].push_back({a, c});
  }
}

bool CrashDetector::BandedPolygon::contains(Vec2 p) const {
  if (bands_.empty() || p.y < y0_) return false;
  const auto k = static_cast<std::size_t>(std::floor((p.y - y0_) / band_m_));
  if (k >= bands_.size()) return false;
  bool inside = false;
  for (const Edge& e : bands_[k]) {
    if ((e.a.y > p.y) != (e.b.y > p.y)) {
      const double x_cross = e.a.x + (p.y - e.a.y) / (e.b.y - e.a.y) * (e.b.x - e.a.x);
      if (p.x < x_cross) inside = !inside;
    }
  }
  return inside;
}

CrashDetector::CrashDetector(const Track& track, Footprint footprint) : footprint_(footprint) {
  if (!(footprint.length_m > 0.0) || !(footprint.width_m > 0.0))
    throw Error("CrashDetector: footprint length and width must be > 0 m");
  use_barriers_ = track.has_barriers();
  if (use_barriers_) {
    for (const Barrier& bar : track.barriers()) {
      const int id = static_cast<int>(barrier_names_.size());
      barrier_names_.push_back(bar.name);
      const std::size_t n = bar.centre.size();
      for (std::size_t i = 0; i < n; ++i) {
        const Vec2 a = bar.centre[i], b = bar.centre[(i + 1) % n];
        const double r = bar.radius_m;
        const Bounds box{std::min(a.x, b.x) - r, std::max(a.x, b.x) + r, std::min(a.y, b.y) - r,
                         std::max(a.y, b.y) + r};
        segments_.push_back({a, b, box, r, id});
      }
    }
  } else {
    inner_ = BandedPolygon(track.inner());
    outer_ = BandedPolygon(track.outer());
  }
}

CrashResult CrashDetector::check(double x_m, double y_m, double yaw_rad) const {
  const OrientedRect rect{{x_m, y_m}, yaw_rad, footprint_.length_m, footprint_.width_m};
  Vec2 corner[4];
  rect.corners(corner);
  CrashResult result;
  if (use_barriers_) {
    Bounds car{corner[0].x, corner[0].x, corner[0].y, corner[0].y};
    for (const Vec2& c : corner) {
      car.x_min = std::min(car.x_min, c.x);
      car.x_max = std::max(car.x_max, c.x);
      car.y_min = std::min(car.y_min, c.y);
      car.y_max = std::max(car.y_max, c.y);
    }
    for (const BarrierSegment& s : segments_) {
      if (s.box.x_max < car.x_min || s.box.x_min > car.x_max || s.box.y_max < car.y_min ||
          s.box.y_min > car.y_max)
        continue;
      const double d = rect_segment_distance(rect, s.a, s.b);
      if (d < s.radius_m) {
        double t = 0.0;
        distance_to_segment(rect.centre, s.a, s.b, &t);
        const Vec2 contact = s.a + t * (s.b - s.a);
        result.crashed = true;
        result.x_m = contact.x;
        result.y_m = contact.y;
        result.reason = "hit the " + barrier_names_[static_cast<std::size_t>(s.barrier)] + " at " +
                        at_point(contact);
        return result;
      }
    }
    return result;
  }
  for (int i = 0; i < 4; ++i) {
    const bool outside_outer = !outer_.contains(corner[i]);
    if (outside_outer || inner_.contains(corner[i])) {
      result.crashed = true;
      result.x_m = corner[i].x;
      result.y_m = corner[i].y;
      result.reason = std::string("left the track: ") + kCornerNames[i] + " corner " +
                      (outside_outer ? "outside the outer" : "inside the inner") + " boundary at " +
                      at_point(corner[i]);
      return result;
    }
  }
  return result;
}

}  // namespace mppi::sim
