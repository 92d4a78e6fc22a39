#pragma once
// Crash detection against a track, for a car with a rectangular footprint.
//  - Tracks with barriers (gazebo): a crash is contact between the footprint rectangle and
//    a barrier pipe, i.e. the rectangle comes closer than the pipe radius to its centreline.
//  - Tracks without barriers (marietta, ccrf): a crash is any footprint corner outside the
//    drivable region (outside the outer boundary or inside the inner one).
// Built for 500 Hz use: barrier segments are pre-boxed and skipped unless their box meets
// the car's, and the point-in-polygon tests only visit the boundary edges of one y-band.
#include <string>
#include <vector>

#include "sim/geometry.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

struct Footprint {
  double length_m = 0.90;  // AutoRally overall length (paper, robot table)
  double width_m = 0.46;   // overall width; the rectangle is centred at the CG
};

struct CrashResult {
  bool crashed = false;
  std::string reason;  // empty when not crashed
  double x_m = 0.0;    // where: the contact point on the barrier / the corner that left
  double y_m = 0.0;
};

class CrashDetector {
 public:
  explicit CrashDetector(const Track& track, Footprint footprint = {});

  // Checks the car at CG (x_m, y_m) heading yaw_rad. Allocates only when it reports a crash.
  CrashResult check(double x_m, double y_m, double yaw_rad) const;

  const Footprint& footprint() const { return footprint_; }

 private:
  struct BarrierSegment {
    Vec2 a, b;
    Bounds box;  // of the segment, grown by the pipe radius
    double radius_m;
    int barrier;
  };
  // Polygon edges bucketed into horizontal bands, for the even-odd ray test along +x.
  class BandedPolygon {
   public:
    BandedPolygon() = default;
    explicit BandedPolygon(const Polyline& polygon, double band_height_m = 0.5);
    bool contains(Vec2 p) const;

   private:
    struct Edge {
      Vec2 a, b;
    };
    double y0_ = 0.0, band_m_ = 1.0;
    std::vector<std::vector<Edge>> bands_;
  };

  Footprint footprint_;
  std::vector<std::string> barrier_names_;
  std::vector<BarrierSegment> segments_;
  bool use_barriers_ = false;
  BandedPolygon inner_, outer_;
};

}  // namespace mppi::sim
