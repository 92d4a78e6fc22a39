#pragma once
// A race track for the simulator: its boundaries, physical barriers (if any), a centreline
// in the driving direction, the start pose and the cost-map file the controller uses.
//
// Built-in tracks (world frame = the frame of AutoRally's cost maps):
//   gazebo   - the Gazebo oval. Its physical walls are two rings of 0.154 m pipe
//              (gazebo_track_barriers.npz, inner_mppi/outer_mppi, tube radius 0.077 m).
//              The rings serve as inner/outer boundary too. (The 2017 track_boundaries.npz of
//              that folder is an older, narrower outline - 63.4 m / 82.0 m around against the
//              pipes' 51.1 m / 72.2 m - that does not match the barrier mesh, so it is not used.)
//   marietta - the real Marietta St. oval: surveyed boundaries, no barriers.
//   ccrf     - the CCRF track: surveyed boundaries, no barriers.
// Tracks without barriers count leaving the region between the boundaries as a crash.
#include <string>
#include <vector>

#include "sim/geometry.hpp"

namespace mppi::sim {

enum class Direction { kCounterClockwise, kClockwise };

struct TrackOptions {
  Direction direction = Direction::kCounterClockwise;  // driving direction; CCW = left turns
  double boundary_spacing_m = 0.05;    // the 5 mm surveyed boundaries are resampled to this
  double centreline_spacing_m = 0.25;  // vertex spacing of the centreline
  std::string data_dir;                // data root; empty = sim::data_dir()
};

// A physical wall: a pipe whose centre follows `centre` (closed), of radius radius_m.
struct Barrier {
  std::string name;
  Polyline centre;
  double radius_m = 0.0;
};

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

class Track {
 public:
  // Loads a built-in track by name ("gazebo", "marietta", "ccrf"). Throws mppi::Error for an
  // unknown name (listing the valid ones) or bad data files (naming file and array).
  static Track load(const std::string& name, const TrackOptions& options = {});
  static std::vector<std::string> names();

  // A track from closed boundary polylines (either orientation; swapped if `inner` is the
  // larger one). Throws mppi::Error if a boundary has < 3 vertices or inner is not inside outer.
  static Track from_boundaries(std::string name, Polyline inner, Polyline outer,
                               std::vector<Barrier> barriers, std::string costmap_path,
                               const TrackOptions& options = {});

  const std::string& name() const { return name_; }
  const std::string& costmap_path() const { return costmap_path_; }
  Direction direction() const { return direction_; }

  // Closed, counter-clockwise boundary polygons (vertices not repeated).
  const Polyline& inner() const { return inner_; }
  const Polyline& outer() const { return outer_; }
  const std::vector<Barrier>& barriers() const { return barriers_; }
  bool has_barriers() const { return !barriers_.empty(); }

  // Closed centreline in the driving direction; vertex 0 is the start, uniformly spaced.
  const Polyline& centreline() const { return centreline_; }
  // Cumulative arc length of the centreline, size = vertices + 1 (last = length_m()).
  const std::vector<double>& centreline_arc_m() const { return centreline_arc_m_; }
  double length_m() const { return centreline_arc_m_.back(); }

  // On the centreline (its vertex 0), heading along the driving direction. Chosen at the
  // middle of the straightest 10 m of the centreline.
  Pose2 start_pose() const { return start_; }

  // Inside outer and outside inner (the region between the boundaries). O(boundary vertices).
  bool is_on_track(Vec2 p) const;
  // Bounding box of boundaries and barriers (with pipe radius).
  Bounds bounds() const;

 private:
  std::string name_;
  std::string costmap_path_;
  Direction direction_ = Direction::kCounterClockwise;
  Polyline inner_, outer_;
  std::vector<Barrier> barriers_;
  Polyline centreline_;
  std::vector<double> centreline_arc_m_;
  Pose2 start_;
};

// Helpers used by Track, exposed for tests.

// Cuts an open, self-overlapping survey polyline (the boundary files run past their start)
// down to one closed loop: the end point is matched to the nearest point of the first quarter
// (or the start point to the last quarter, whichever gap is smaller) and the overlap dropped.
// Throws mppi::Error naming `what` if the ends are more than max_gap_m apart.
Polyline close_loop(const Polyline& raw, double max_gap_m, const std::string& what);

// Centreline between two closed boundaries: midpoints from each point of the inner boundary
// (resampled to 5 cm) to the nearest outer boundary point, then resampled to spacing_m and
// smoothed a little. Same orientation as `inner`.
Polyline centreline_between(const Polyline& inner, const Polyline& outer, double spacing_m);

}  // namespace mppi::sim
