#pragma once
// PNG plot of a run on a track: boundaries / barriers, the centreline (dashed), the start,
// the driven path coloured by speed (turbo colour map, colour bar with min/max labels),
// crash points as red crosses and a title. World y points up in the image.
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

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

// The world -> pixel mapping and size of a track plot (the same for every run on a track,
// so plots of different runs overlay).
class PlotFrame {
 public:
  // title_lines: number of lines of the title band at the top.
  PlotFrame(const Track& track, int width_px = 1000, int title_lines = 1);

  int width_px() const { return width_px_; }
  int height_px() const { return height_px_; }
  double px_per_m() const { return px_per_m_; }
  // {column, row} of the world point (x_m, y_m), rounded to the nearest pixel.
  std::pair<int, int> to_pixel(double x_m, double y_m) const;
  // Horizontal extent of the map and of the colour-bar panel on its right.
  int map_right_px() const { return map_right_px_; }

 private:
  int width_px_ = 0, height_px_ = 0, map_right_px_ = 0;
  double px_per_m_ = 1.0;
  double x_min_m_ = 0.0, y_max_m_ = 0.0;
  int left_px_ = 0, top_px_ = 0;
};

// Speed colour of the plot for speed v on the scale [v_min, v_max] (clamped), as RGB.
std::array<std::uint8_t, 3> speed_colour_rgb(double v, double v_min, double v_max);

// Writes the plot. `title` may hold several lines separated by '\n'. Throws mppi::Error if
// the PNG cannot be written.
void plot_track_run(const std::string& png_path, const Track& track,
                    const std::vector<PathSample>& path,
                    const std::vector<std::pair<float, float>>& crash_points,
                    const std::string& title, const PlotOptions& options = {});

// An 8-bit RGB image read back from a file (for tests and tools that check plots).
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, 3 bytes per pixel
  std::array<std::uint8_t, 3> at(int column, int row) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                               static_cast<std::size_t>(column));
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};
// Throws mppi::Error if the file cannot be read as an image.
RgbImage read_image_rgb(const std::string& path);

}  // namespace mppi::sim
