#pragma once
// mppi-sim --limit-lap: the limit lap (sim/limit_lap.hpp) of the plant's vehicle file on the
// run's track, printed and written as a table and a figure.
#include <optional>
#include <string>

#include "sim/closed_loop.hpp"
#include "sim/limit_lap.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

// CSV with a header line: s_m, x_m, y_m, curvature_1pm, speed_mps, ax_mps2, ay_mps2, one row per
// station. Throws mppi::Error if the file cannot be written.
void write_limit_lap_csv(const std::string& path, const LimitLap& lap);

// The racing line coloured by speed on the track (sim/track_plot.hpp). Throws mppi::Error if the
// PNG cannot be written.
void plot_limit_lap(const std::string& png_path, const Track& track, const LimitLap& lap, const std::string& title);

// Lap time, length, mean / max / min speed, one line each.
std::string describe_limit_lap(const LimitLap& lap);

// The flying limit lap and the one from a standing start at the start line (the closed loop's
// lap 1); none where the method finds no standing-start lap, with the reason.
struct LimitLaps {
  LimitLap flying;
  std::optional<LimitLap> standing;
  std::string standing_error;
};

// describe_limit_lap of the flying lap, then the standing-start lap's time and mean speed
// ("standing-start lap  9.05 s ...", or "standing-start lap  none: <reason>").
std::string describe_limit_laps(const LimitLaps& laps);

// The limit laps of config's plant (plant_vehicle_params) on config's track and direction; with
// config.out_dir set, writes out_dir/limit_lap.csv and out_dir/limit_lap.png (the flying lap) and
// out_dir/standing_limit_lap.csv. Throws mppi::Error for a plant without single-track parameters
// (naming it), bad data files, or a method that finds no flying lap.
LimitLaps report_limit_lap(const ClosedLoopConfig& config);

}  // namespace mppi::sim
