#include "sim/lap_counter.hpp"

#include <algorithm>
#include <cmath>

#include "base/error.hpp"

namespace mppi::sim {

LapCounter::LapCounter(const Track& track, LapCounterOptions options)
    : LapCounter(track.centreline(), options) {}

LapCounter::LapCounter(Polyline centreline, LapCounterOptions options)
    : line_(std::move(centreline)), options_(options) {
  if (line_.size() < 3) throw Error("LapCounter: centreline needs at least 3 vertices");
  arc_ = cumulative_arc_length(line_, true);
  if (!(arc_.back() > 0.0)) throw Error("LapCounter: centreline has zero length");
  if (!(options_.search_window_m > 0.0) || !(options_.max_jump_m > 0.0))
    throw Error("LapCounter: search_window_m and max_jump_m must be > 0");
  const double mean_segment_m = arc_.back() / static_cast<double>(line_.size());
  window_segments_ = std::clamp<std::size_t>(
      static_cast<std::size_t>(std::ceil(options_.search_window_m / mean_segment_m)), 2,
      line_.size() / 2);
}

double LapCounter::arc_of(const ClosestPoint& c) const {
  return arc_[c.segment] + c.t * (arc_[c.segment + 1] - arc_[c.segment]);
}

ClosestPoint LapCounter::search(Vec2 p, bool local) const {
  if (!local) return closest_point(line_, true, p);
  const auto w = static_cast<std::ptrdiff_t>(window_segments_);
  const ClosestPoint c = closest_point_in_range(line_, true, p,
                                                static_cast<std::ptrdiff_t>(segment_) - w,
                                                window_segments_ * 2 + 1);
  // A match on the window's first or last segment may be a boundary effect (the true minimum
  // lies outside), and a far one means the car is not where we thought: search everything.
  const std::size_t n = line_.size();
  const std::size_t first = (segment_ + n - window_segments_) % n;
  const std::size_t last = (segment_ + window_segments_) % n;
  if (c.segment == first || c.segment == last || c.distance_m > options_.lost_distance_m)
    return closest_point(line_, true, p);
  return c;
}

void LapCounter::reset(Vec2 p, double t_s) {
  const ClosestPoint c = search(p, false);
  segment_ = c.segment;
  arc_m_ = arc_of(c);
  lateral_m_ = c.distance_m;
  const double length = length_m();
  progress_m_ = arc_m_ >= 0.5 * length ? arc_m_ - length : arc_m_;
  last_t_s_ = t_s;
  lap_start_t_s_ = t_s;
  lap_times_s_.clear();
  rejected_jumps_ = 0;
  started_ = true;
}

void LapCounter::update(Vec2 p, double t_s) {
  if (!started_) {
    reset(p, t_s);
    return;
  }
  const ClosestPoint c = search(p, true);
  const double arc = arc_of(c);
  const double length = length_m();
  double delta = arc - arc_m_;  // wrapped to [-length/2, length/2)
  delta -= length * std::floor(delta / length + 0.5);
  segment_ = c.segment;
  arc_m_ = arc;
  lateral_m_ = c.distance_m;
  if (std::abs(delta) > options_.max_jump_m) {
    ++rejected_jumps_;  // re-anchored, but the jump does not count as progress
    last_t_s_ = t_s;
    return;
  }
  const double before = progress_m_;
  progress_m_ += delta;
  // Count each lap line the first time it is passed going forward.
  while (progress_m_ >= length * static_cast<double>(laps_completed() + 1)) {
    const double line = length * static_cast<double>(laps_completed() + 1);
    const double frac = delta > 0.0 ? std::clamp((line - before) / delta, 0.0, 1.0) : 1.0;
    const double t_cross = last_t_s_ + frac * (t_s - last_t_s_);
    lap_times_s_.push_back(t_cross - lap_start_t_s_);
    lap_start_t_s_ = t_cross;
  }
  last_t_s_ = t_s;
}

}  // namespace mppi::sim
