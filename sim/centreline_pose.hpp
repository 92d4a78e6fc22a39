#pragma once
// Where a marshal puts a car back: the point of the track's centreline nearest to it, facing
// along the centreline's segment there (the driving direction).
#include <cmath>

#include "sim/geometry.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

inline Pose2 centreline_pose_nearest(const Track& track, Vec2 p) {
  const Polyline& centre = track.centreline();
  const ClosestPoint c = closest_point(centre, true, p);
  const Vec2 a = centre[c.segment];
  const Vec2 b = centre[(c.segment + 1) % centre.size()];
  return {c.point.x, c.point.y, std::atan2(b.y - a.y, b.x - a.x)};
}

}  // namespace mppi::sim
