#pragma once
// A minimum-curvature racing line on a track: lateral offsets n_i along the normals of the
// centreline (resampled to uniform stations), bounded by the local half-widths less a margin,
// that minimise the sum of the squared curvatures kappa_i^2 of the line p_i = c_i + n_i N_i
// (kappa_i: the circle through p_{i-1}, p_i, p_{i+1}), optionally plus a weighted length term.
// Gauss-Newton with Levenberg-Marquardt
// damping from the centreline; each step a quadratic programme with box constraints, solved by
// a primal-dual active-set method with Eigen's sparse LDL^T. Stations where the line comes closer than the margin to a boundary (the normal
// meets it obliquely) get a tighter bound and the programme is solved again.
#include <vector>

#include "sim/geometry.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

struct RacingLineOptions {
  double margin_m = 0.5;            // least distance from the line to either boundary [m]
  double station_spacing_m = 0.5;   // centreline stations, about this far apart [m]
  int max_iterations = 200;         // active-set iterations per quadratic programme
  // Trades curvature for length: adds w sum |p_{i+1} - p_i|^2 / h^2 (h the spacing; the sum is
  // least on the shortest line) to the sum of squared curvatures [1/m^2]; 0 = the minimum-curvature
  // line, large = towards the shortest line. Both sums grow alike with the number of stations.
  double length_weight_1pm2 = 0.0;
};

struct RacingLine {
  Polyline centre;                  // the stations on the centreline c_i (closed, uniform)
  Polyline normal;                  // unit left normals N_i at the stations
  std::vector<double> left_m;       // half-width to the first boundary along +N_i
  std::vector<double> right_m;      // along -N_i
  std::vector<double> offset_m;     // n_i, in [-(right - margin), left - margin]
  Polyline line;                    // p_i = c_i + n_i N_i (closed)
};

// Half-widths of the track along the normals of the closed polyline `centre`: distance from
// each vertex to the first crossing of either boundary along +N (left) and -N (right).
// Throws mppi::Error if a ray meets no boundary.
void track_half_widths(const Track& track, const Polyline& centre, const Polyline& normal,
                       std::vector<double>* left_m, std::vector<double>* right_m);

// Unit left normals of a closed polyline (central differences of its vertices).
Polyline left_normals(const Polyline& closed_line);

// The racing line. Throws mppi::Error for bad options (naming them) or a track narrower than
// twice the margin somewhere (naming the station and its arc length).
RacingLine racing_line(const Track& track, const RacingLineOptions& options = {});

// Signed curvature at each vertex of a closed polyline (Menger: the circle through the vertex
// and its neighbours; left turns positive) and the distance from each vertex to the next.
void closed_line_curvature(const Polyline& line, std::vector<double>* curvature_1pm, std::vector<double>* ds_m);

}  // namespace mppi::sim
