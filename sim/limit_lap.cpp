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

}  // namespace

LimitLap lap_on_line(const Polyline& closed_line, const CarLimits& limits) {
  CarLimits closed = limits;
  closed.closed = true;
  LimitLap lap;
  std::vector<double> ds_m;
  closed_line_curvature(closed_line, &lap.curvature_1pm, &ds_m);
  QssProfile profile = qss_speed_profile(ds_m, lap.curvature_1pm, closed);
  lap.lap_time_s = profile.time_s;
  lap.speed_mps = std::move(profile.speed_mps);
  lap.ax_mps2 = std::move(profile.ax_mps2);
  lap.ay_mps2 = std::move(profile.ay_mps2);
  const std::size_t n = closed_line.size();
  lap.s_m.resize(n);
  lap.x_m.resize(n);
  lap.y_m.resize(n);
  double s = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    lap.s_m[i] = s;
    lap.x_m[i] = closed_line[i].x;
    lap.y_m[i] = closed_line[i].y;
    s += ds_m[i];
  }
  lap.length_m = s;
  lap.mean_speed_mps = s / lap.lap_time_s;
  lap.max_speed_mps = *std::max_element(lap.speed_mps.begin(), lap.speed_mps.end());
  lap.min_speed_mps = *std::min_element(lap.speed_mps.begin(), lap.speed_mps.end());
  return lap;
}

LimitLap limit_lap(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options) {
  validate(options);
  const CarLimits limits = car_limits(vehicle);
  RacingLineOptions line;
  line.margin_m = options.car_half_width_m + options.safety_margin_m;
  line.station_spacing_m = options.station_spacing_m;
  line.max_iterations = options.max_iterations;
  LimitLap best;
  for (double weight : options.length_weights_1pm2) {
    line.length_weight_1pm2 = weight;
    LimitLap lap = lap_on_line(racing_line(track, line).line, limits);
    lap.length_weight_1pm2 = weight;
    if (best.s_m.empty() || lap.lap_time_s < best.lap_time_s) best = std::move(lap);
  }
  return best;
}

LimitLap centreline_lap(const Track& track, const SingleTrackParams& vehicle, const LimitLapOptions& options) {
  validate(options);
  return lap_on_line(resample(track.centreline(), true, options.station_spacing_m), car_limits(vehicle));
}

}  // namespace mppi::sim
