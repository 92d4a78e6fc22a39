#pragma once
// PNG figures of `mppi-fit estimate` (OpenCV): small-multiple line charts, one panel per
// parameter or channel, white background, Hershey text like sim/track_plot.
#include <string>
#include <vector>

namespace mppi::sysid {

struct PlotSeries {
  std::vector<double> x, y;
  int colour = 0;  // index into the palette: 0 dark blue, 1 orange, 2 green, 3 red, 4 grey
  std::string label;
  bool dashed = false;
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::vector<PlotSeries> series;
  std::vector<double> hlines;  // horizontal reference lines (e.g. the true value), grey dashed
  bool equal_axes = false;     // same scale on x and y (a path in the plane)
};

// Panels in a grid of `columns`; each panel panel_w x panel_h pixels; a title band on top.
// Throws mppi::Error if the file cannot be written.
void write_panels_png(const std::string& path, const std::string& title, const std::vector<PlotPanel>& panels,
                      int columns = 3, int panel_w = 420, int panel_h = 260);

}  // namespace mppi::sysid
