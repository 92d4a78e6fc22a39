#pragma once
// Surface maps: grip (a friction scale on the tyre forces, 1 = the model's own tyre) and
// elevation (ground height z [m]) by place on the track, so that a simulated car meets
// slippery patches and hills. Loaded from a YAML file (docs/SURFACES.md):
//
//   track: gazebo                 # needed only for arc-length patches
//   grip:
//     default: 1.0
//     patches:
//       - {centre_m: [-5.0, 10.0], radius_m: 3.0, value: 0.5, edge_m: 1.0}   # a disc
//       - {arc_m: [20.0, 32.0], value: 0.7, edge_m: 2.0}                        # a stretch
//   elevation:
//     grade: [0.02, 0.0]          # plane z += g_x x + g_y y
//     patches:
//       - {centre_m: [0.0, 0.0], radius_m: 8.0, value: 0.4}   # a hill: raised cosine, 0.4 m high
//
// or, per layer, a grayscale image placed like the cost maps:
//   grip: {image: grip.png, origin_m: [x0, y0], resolution_m: 0.1, black: 0.5, white: 1.0}
// (pixel (col, row) covers x0 + col res .. x0 + (col+1) res and, row 0 being the TOP row,
// y0 + (rows-1-row) res .. y0 + (rows-row) res; its value is taken at the cell centre and
// interpolated bilinearly; outside the image the layer's default).
//
// Grip patches blend into the value around them over edge_m (smoothstep), later patches on
// top of earlier ones; elevation patches add up. Arc-length patches cover the places whose
// closest point on the track's counter-clockwise centreline lies in [arc0, arc1] (arc0 > arc1
// wraps past the start), within half_width_m of it (default: anywhere).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/geometry.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

struct SurfacePatch {
  enum class Shape { kDisc, kArc } shape = Shape::kDisc;
  Vec2 centre_m;                 // disc
  double radius_m = 0;           // disc
  double arc0_m = 0, arc1_m = 0; // arc range along the CCW centreline
  double half_width_m = 1e9;     // arc: lateral extent from the centreline
  double value = 1;              // grip scale, or hill height [m]
  double edge_m = 0;             // grip: blend width outside the patch
};

struct SurfaceImage {
  std::vector<float> values;  // row-major, row 0 = lowest y
  int cols = 0, rows = 0;
  Vec2 origin_m;              // lower-left corner of the image
  double resolution_m = 0.1;  // cell size
  double bilinear(double x, double y, double outside) const;
};

struct SurfaceLayer {
  double default_value = 0;
  double grade_x = 0, grade_y = 0;      // elevation only: a plane
  std::vector<SurfacePatch> patches;
  std::optional<SurfaceImage> image;
};

class SurfaceMap {
 public:
  SurfaceMap();  // flat, grip 1 everywhere
  // Reads the YAML above; images are relative to the file. Throws mppi::Error naming the file
  // and key for a malformed file, an unreadable image or arc patches without a track.
  static SurfaceMap load(const std::string& path);
  // From layers already built (tests, generators). `centreline` is the CCW centreline for arc
  // patches, with its cumulative arc lengths (as Track gives them); may be empty.
  SurfaceMap(SurfaceLayer grip, SurfaceLayer elevation, Polyline centreline = {},
             std::vector<double> centreline_arc_m = {});

  double grip(double x_m, double y_m) const;          // friction scale [-], > 0
  double elevation_m(double x_m, double y_m) const;   // ground height [m]
  // Slope of the ground (dz/dx, dz/dy), central differences of elevation over 5 cm.
  Vec2 slope(double x_m, double y_m) const;
  // Gravity along the ground, in the body frame of a car at (x, y) heading yaw [m/s^2]:
  // -g d / sqrt(1 + d^2) along each body axis e, d = slope . e (g sin(theta) down the slope).
  Vec2 gravity_body_mps2(double x_m, double y_m, double yaw_rad, double g_mps2 = 9.81) const;
  bool flat() const;  // no elevation at all

  const SurfaceLayer& grip_layer() const { return grip_; }
  const SurfaceLayer& elevation_layer() const { return elevation_; }

 private:
  double arc_and_offset(Vec2 p, double* lateral_m) const;
  double patch_weight(const SurfacePatch& patch, Vec2 p, bool smooth_edge) const;
  SurfaceLayer grip_, elevation_;
  Polyline centreline_;
  std::vector<double> arc_m_;
};

}  // namespace mppi::sim
