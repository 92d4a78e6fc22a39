#include "sim/limit_lap_report.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <vector>

#include "base/error.hpp"
#include "sim/limit_lap_methods.hpp"
#include "sim/track_plot.hpp"

namespace mppi::sim {

void write_limit_lap_csv(const std::string& path, const LimitLap& lap) {
  std::ofstream out(path, std::ios::out | std::ios::trunc);
  if (!out) throw Error(path + ": cannot open for writing");
  out << "s_m,x_m,y_m,curvature_1pm,speed_mps,ax_mps2,ay_mps2\n";
  char row[256];
  for (std::size_t i = 0; i < lap.s_m.size(); ++i) {
    std::snprintf(row, sizeof row, "%.4f,%.4f,%.4f,%.6f,%.4f,%.4f,%.4f\n", lap.s_m[i], lap.x_m[i], lap.y_m[i],
                  lap.curvature_1pm[i], lap.speed_mps[i], lap.ax_mps2[i], lap.ay_mps2[i]);
    out << row;
  }
  out.close();
  if (!out) throw Error(path + ": write failed");
}

void plot_limit_lap(const std::string& png_path, const Track& track, const LimitLap& lap, const std::string& title) {
  std::vector<PathSample> path;
  for (std::size_t i = 0; i <= lap.s_m.size() && !lap.s_m.empty(); ++i) {  // closed: back to the start
    const std::size_t j = i % lap.s_m.size();
    path.push_back({static_cast<float>(lap.x_m[j]), static_cast<float>(lap.y_m[j]), static_cast<float>(lap.speed_mps[j])});
  }
  plot_track_run(png_path, track, path, {}, title);
}

std::string describe_limit_lap(const LimitLap& lap) {
  char text[512];
  std::snprintf(text, sizeof text,
                "lap time    %.2f s\nline        %.1f m\nmean speed  %.2f m/s\nmax speed   %.2f m/s\nmin speed   %.2f m/s\n",
                lap.lap_time_s, lap.length_m, lap.mean_speed_mps, lap.max_speed_mps, lap.min_speed_mps);
  return text;
}

std::string describe_limit_laps(const LimitLaps& laps) {
  if (!laps.standing) return describe_limit_lap(laps.flying) + "standing-start lap  none: " + laps.standing_error + "\n";
  char text[256];
  std::snprintf(text, sizeof text, "standing-start lap  %.2f s (from rest at the start line; mean %.2f m/s, max %.2f m/s)\n",
                laps.standing->lap_time_s, laps.standing->mean_speed_mps, laps.standing->max_speed_mps);
  return describe_limit_lap(laps.flying) + text;
}

LimitLaps report_limit_lap(const ClosedLoopConfig& config) {
  const std::optional<SingleTrackParams> vehicle = plant_vehicle_params(config);
  if (!vehicle)
    throw Error("the plant '" + config.plant + "' has no single-track parameters, so no limit lap (single-track, "
                "double-track and full-vehicle plants have)");
  TrackOptions track_options;
  track_options.direction = config.clockwise ? Direction::kClockwise : Direction::kCounterClockwise;
  const Track track = Track::load(config.track, track_options);
  LimitLaps laps;
  laps.flying = limit_lap_by_method(config.limit_lap_method, track, *vehicle, LapStart::kFlying);
  try {
    laps.standing = limit_lap_by_method(config.limit_lap_method, track, *vehicle, LapStart::kStanding);
  } catch (const Error& e) {
    laps.standing_error = e.what();
  }
  const LimitLap& lap = laps.flying;
  if (!config.out_dir.empty()) {
    std::filesystem::create_directories(config.out_dir);
    write_limit_lap_csv(config.out_dir + "/limit_lap.csv", lap);
    if (laps.standing) write_limit_lap_csv(config.out_dir + "/standing_limit_lap.csv", *laps.standing);
    char title[256];
    std::snprintf(title, sizeof title, "%s | limit lap (%s) of the %s plant: %.2f s, mean %.2f m/s", track.name().c_str(),
                  config.limit_lap_method.c_str(), config.plant.c_str(), lap.lap_time_s, lap.mean_speed_mps);
    plot_limit_lap(config.out_dir + "/limit_lap.png", track, lap, title);
  }
  return laps;
}

}  // namespace mppi::sim
