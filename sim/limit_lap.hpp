#pragma once
// The car's limit lap on a track: the minimum-time lap of a quasi-steady-state (QSS) lap
// simulation (sim/qss_speed_profile.hpp) on a minimum-curvature racing line
// (sim/racing_line.hpp), curvature traded for length where that is faster, that keeps half the
// car's width and a safety margin from both boundaries. docs/LIMIT_LAP.md gives the method and the tracks' figures.
#include <vector>

#include "dynamics/vehicle_params.hpp"
#include "sim/geometry.hpp"
#include "sim/qss_speed_profile.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

struct LimitLapOptions {
  double car_half_width_m = 0.3;    // the line keeps this plus the safety margin from both boundaries
  double safety_margin_m = 0.2;
  double station_spacing_m = 0.5;   // stations along the centreline [m]
  int max_iterations = 200;         // active-set iterations of the racing line's programme
  // The racing lines tried, from minimum curvature (0) towards the shortest line
  // (RacingLineOptions::length_weight_1pm2): the fastest lap of them is the limit lap.
  std::vector<double> length_weights_1pm2 = {0.0, 0.02, 0.04, 0.08, 0.16, 0.32};
};

// A lap: per station the arc length along the line, the point, curvature, speed and
// accelerations (sim/qss_speed_profile.hpp: ax from the station to the next).
struct LimitLap {
  double lap_time_s = 0.0;
  double length_m = 0.0;            // of the line
  std::vector<double> s_m, x_m, y_m, curvature_1pm, speed_mps, ax_mps2, ay_mps2;
  double mean_speed_mps = 0.0;      // length / lap time
  double max_speed_mps = 0.0;
  double min_speed_mps = 0.0;
  double length_weight_1pm2 = 0.0;  // of the racing line (limit_lap)
  // A standing start: from rest at the first station, the stations running once round to the
  // start again (the last repeats the first's point); else a flying lap (closed, periodic).
  bool standing_start = false;
  // The part of lap_time_s not on the stations: the collocation's closed-form run from rest to its
  // first station's speed (laptime/min_time_lap.hpp); 0 for the QSS lap, whose profile starts at 0.
  double launch_time_s = 0.0;
};

// The QSS lap of a car on a closed line (vertices in the driving direction, curvature by
// closed_line_curvature). Throws mppi::Error for a line with fewer than 3 vertices or limits
// that qss_speed_profile refuses (limits.closed is taken as true).
LimitLap lap_on_line(const Polyline& closed_line, const CarLimits& limits);

// The QSS lap from rest at the line's vertex 0 once round to it again (an open path of the
// closed line's vertices and the first one repeated; start speed 0, end speed free):
// LimitLap::standing_start, one station more than lap_on_line's. Throws as lap_on_line.
LimitLap standing_lap_on_line(const Polyline& closed_line, const CarLimits& limits);

// The limit lap: the fastest QSS lap of car_limits(vehicle) on the racing lines of
// racing_line(track) with margin car_half_width_m + safety_margin_m and each of the length
// weights. Throws mppi::Error for bad options or parameters
// (naming them) or a track too narrow for the margin.
LimitLap limit_lap(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options = {});

// The standing-start limit lap: as limit_lap, the fastest standing_lap_on_line of the same racing
// lines, from rest at the track's start line (centreline vertex 0, where the closed loop spawns the
// car and counts its laps) once round to it. The QSS car is a point on the line: it does not see
// that the closed loop's car starts on the centreline rather than on the racing line.
LimitLap standing_limit_lap(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options = {});

// Both at once, each racing line computed once: what limit_lap and standing_limit_lap return.
struct QssLimitLaps {
  LimitLap flying, standing;
};
QssLimitLaps flying_and_standing_limit_laps(const Track& track, const SingleTrackParams& vehicle,
                                         const LimitLapOptions& options = {});

// The same car's QSS lap on the track's centreline (resampled to the same stations): what the
// racing line is measured against.
LimitLap centreline_lap(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options = {});

}  // namespace mppi::sim
