#pragma once
// The report's figures (drawn by mppi::plot): residual vs regime before / after, and a held-out
// trajectory overlay (measured vs nominal vs corrected open-loop predictions). The same Figure
// goes to a PNG, to report.json and to the interactive report.html.
#include <string>
#include <vector>

#include "diagnose/data.hpp"
#include "diagnose/locate.hpp"
#include "diagnose/replay.hpp"
#include "plot/figure.hpp"

namespace mppi::diagnose {

// Grid: rows = channels, columns = speed, steer, throttle, lateral accel; per panel the mean
// residual per regime bin before (red) and after (blue), on rows in mask (held out).
plot::Figure residual_vs_regime_figure(const PreparedRecording& d, const ResidualSeries& before, const ResidualSeries& after,
                                       const std::vector<char>& mask);

// Top: x-y of the held-out part with 2-s open-loop predictions every 1 s (nominal red,
// corrected blue, measured black); below: vx and yaw rate against time with the 1-s-ahead
// predictions. Long series are thinned to about a thousand points.
plot::Figure overlay_figure(const PreparedRecording& d, const ReplayModel& nominal, const ReplayModel& corrected,
                            const std::vector<char>& mask, const ReplayOptions& o);

// The figures written as PNGs.
void plot_residual_vs_regime(const std::string& png, const PreparedRecording& d, const ResidualSeries& before,
                             const ResidualSeries& after, const std::vector<char>& mask);
void plot_overlay(const std::string& png, const PreparedRecording& d, const ReplayModel& nominal,
                  const ReplayModel& corrected, const std::vector<char>& mask, const ReplayOptions& o);

}  // namespace mppi::diagnose
