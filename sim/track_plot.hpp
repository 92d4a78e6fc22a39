#pragma once
// PNG plot of a run on a track (drawn by mppi::plot): barriers or boundaries, the centreline
// (dashed), the start, the driven path coloured by speed (turbo colour map, colour bar), crash
// points as red crosses, x / y axes in metres at the same scale, a legend and a title.
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "plot/figure.hpp"
#include "plot/png_image.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

struct PathSample {
  float x_m = 0.f;
  float y_m = 0.f;
  float speed_mps = 0.f;
};

struct PlotOptions {
  int width_px = 1000;             // image width; the height follows the track's aspect ratio
  double speed_min_mps = 0.0;      // colour scale; min == max (default) = the path's range
  double speed_max_mps = 0.0;
  // What the trail's colour shows (PathSample::speed_mps holds its value): colour-bar title
  // and unit, e.g. "body slip" and "deg" for a slip-angle plot.
  std::string quantity = "speed";
  std::string unit = "m/s";
};

// Speed colour of the plot for speed v on the scale [v_min, v_max] (clamped), as RGB.
std::array<std::uint8_t, 3> speed_colour_rgb(double v, double v_min, double v_max);

// The figure plot_track_run writes (one equal-scale panel).
plot::Figure track_run_figure(const Track& track, const std::vector<PathSample>& path,
                              const std::vector<std::pair<float, float>>& crash_points,
                              const std::string& title, const PlotOptions& options = {});

// Writes the plot. `title` may hold several lines separated by '\n'. Throws mppi::Error if
// the PNG cannot be written.
void plot_track_run(const std::string& png_path, const Track& track,
                    const std::vector<PathSample>& path,
                    const std::vector<std::pair<float, float>>& crash_points,
                    const std::string& title, const PlotOptions& options = {});

// An 8-bit RGB image read back from a file (for tests and tools that check plots).
using plot::RgbImage;
using plot::read_image_rgb;

}  // namespace mppi::sim
