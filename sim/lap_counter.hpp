#pragma once
// Progress along the track's centreline and lap counting.
//
// Progress is the arc length of the closest centreline point, unwrapped (metres since the
// start, negative when driving backwards over the start line). The closest point is searched
// only near the previous one, so an update is cheap and cannot jump to another part of the
// track that passes nearby. If the car leaves that neighbourhood (it cut across the infield,
// or was moved), the counter re-anchors with a full search and the jump is NOT counted as
// progress. A lap counts when progress first passes k * length for a new k, so driving
// backwards and forwards over the line does not count it twice.
#include <cstddef>
#include <vector>

#include "sim/geometry.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

struct LapCounterOptions {
  double search_window_m = 5.0;     // local search spans +- this much arc length
  double max_jump_m = 5.0;          // larger progress changes in one update are rejected
  double lost_distance_m = 3.0;     // farther than this from the local match: full search
};

class LapCounter {
 public:
  // Uses the track's centreline; progress 0 at its vertex 0 (the start line).
  explicit LapCounter(const Track& track, LapCounterOptions options = {});
  // Any closed centreline in the driving direction (for tests and custom tracks).
  explicit LapCounter(Polyline centreline, LapCounterOptions options = {});

  // Starts counting at time t_s from position p (full search for the closest point). The
  // initial progress is p's arc length from the start line, wrapped to [-length/2, length/2).
  void reset(Vec2 p, double t_s);
  // Feeds one position at time t_s (t_s should increase). Calls reset() on the first call.
  void update(Vec2 p, double t_s);

  double progress_m() const { return progress_m_; }       // unwrapped, from the start line
  double arc_m() const { return arc_m_; }                 // current position along [0, length)
  double lateral_error_m() const { return lateral_m_; }   // distance to the centreline
  double length_m() const { return arc_.back(); }
  int laps_completed() const { return static_cast<int>(lap_times_s_.size()); }
  // Duration of each completed lap (crossing times interpolated between updates).
  const std::vector<double>& lap_times_s() const { return lap_times_s_; }
  // Updates whose progress jump was rejected (cut across / teleported).
  int rejected_jumps() const { return rejected_jumps_; }

 private:
  ClosestPoint search(Vec2 p, bool local) const;
  double arc_of(const ClosestPoint& c) const;

  Polyline line_;
  std::vector<double> arc_;
  LapCounterOptions options_;
  std::size_t window_segments_ = 0;
  bool started_ = false;
  std::size_t segment_ = 0;
  double arc_m_ = 0.0;
  double progress_m_ = 0.0;
  double lateral_m_ = 0.0;
  double last_t_s_ = 0.0;
  double lap_start_t_s_ = 0.0;
  std::vector<double> lap_times_s_;
  int rejected_jumps_ = 0;
};

}  // namespace mppi::sim
