#include "sim/limit_lap.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "base/error.hpp"
#include "sim/racing_line.hpp"

namespace mppi::sim {
namespace {

void validate(const LimitLapOptions& o) {
  if (!(std::isfinite(o.car_half_width_m) && o.car_half_width_m >= 0.0))
    throw Error("limit_lap: car_half_width_m must be finite and >= 0");
  if (!(std::isfinite(o.safety_margin_m) && o.safety_margin_m >= 0.0))
    throw Error("limit_lap: safety_margin_m must be finite and >= 0");
  if (!(std::isfinite(o.station_spacing_m) && o.station_spacing_m > 0.0))
    throw Error("limit_lap: station_spacing_m must be finite and > 0");
  if (o.length_weights_1pm2.empty()) throw Error("limit_lap: length_weights_1pm2 is empty");
  for (double w : o.length_weights_1pm2)
    if (!(std::isfinite(w) && w >= 0.0)) throw Error("limit_lap: length_weights_1pm2 must be finite and >= 0");
}

// The QSS lap on a closed line, flying (periodic) or from rest at vertex 0 once round to it.
LimitLap qss_lap(const Polyline& closed_line, const CarLimits& limits, bool standing_start) {
  LimitLap lap;
  std::vector<double> ds_m;
  closed_line_curvature(closed_line, &lap.curvature_1pm, &ds_m);
  Polyline points = closed_line;
  CarLimits car = limits;
  car.closed = !standing_start;
  if (standing_start) {  // an open path ending where it started
    lap.curvature_1pm.push_back(lap.curvature_1pm.front());
    points.push_back(closed_line.front());
    car.start_speed_mps = 0.0;
    car.end_speed_mps = CarLimits::kInf;
  }
  QssProfile profile = qss_speed_profile(ds_m, lap.curvature_1pm, car);
  lap.standing_start = standing_start;
  lap.lap_time_s = profile.time_s;
  lap.speed_mps = std::move(profile.speed_mps);
  lap.ax_mps2 = std::move(profile.ax_mps2);
  lap.ay_mps2 = std::move(profile.ay_mps2);
  const std::size_t n = points.size();
  lap.s_m.resize(n);
  lap.x_m.resize(n);
  lap.y_m.resize(n);
  double s = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    lap.s_m[i] = s;
    lap.x_m[i] = points[i].x;
    lap.y_m[i] = points[i].y;
    if (i < ds_m.size()) s += ds_m[i];
  }
  lap.length_m = s;
  lap.mean_speed_mps = s / lap.lap_time_s;
  lap.max_speed_mps = *std::max_element(lap.speed_mps.begin(), lap.speed_mps.end());
  lap.min_speed_mps = *std::min_element(lap.speed_mps.begin(), lap.speed_mps.end());
  return lap;
}

// The fastest QSS laps, flying and standing, of the racing lines of options' length weights.
QssLimitLaps fastest_racing_line_laps(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options,
                                   bool flying, bool standing) {
  validate(options);
  const CarLimits limits = car_limits(vehicle);
  RacingLineOptions line;
  line.margin_m = options.car_half_width_m + options.safety_margin_m;
  line.station_spacing_m = options.station_spacing_m;
  line.max_iterations = options.max_iterations;
  QssLimitLaps best;
  auto keep_faster = [](LimitLap lap, double weight, LimitLap* kept) {
    lap.length_weight_1pm2 = weight;
    if (kept->s_m.empty() || lap.lap_time_s < kept->lap_time_s) *kept = std::move(lap);
  };
  for (double weight : options.length_weights_1pm2) {
    line.length_weight_1pm2 = weight;
    const Polyline racing = racing_line(track, line).line;
    if (flying) keep_faster(qss_lap(racing, limits, false), weight, &best.flying);
    if (standing) keep_faster(qss_lap(racing, limits, true), weight, &best.standing);
  }
  return best;
}

}  // namespace

LimitLap lap_on_line(const Polyline& closed_line, const CarLimits& limits) {
  return qss_lap(closed_line, limits, false);
}

LimitLap standing_lap_on_line(const Polyline& closed_line, const CarLimits& limits) {
  return qss_lap(closed_line, limits, true);
}

LimitLap limit_lap(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options) {
  return fastest_racing_line_laps(track, vehicle, options, true, false).flying;
}

LimitLap standing_limit_lap(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options) {
  return fastest_racing_line_laps(track, vehicle, options, false, true).standing;
}

QssLimitLaps flying_and_standing_limit_laps(const Track& track, const SingleTrackParams& vehicle,
                                         const LimitLapOptions& options) {
  return fastest_racing_line_laps(track, vehicle, options, true, true);
}

LimitLap centreline_lap(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options) {
  validate(options);
  return lap_on_line(resample(track.centreline(), true, options.station_spacing_m), car_limits(vehicle));
}

}  // namespace mppi::sim
