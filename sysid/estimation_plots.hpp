#pragma once
// PNG figures of `mppi-fit estimate` (drawn by mppi::plot): small-multiple line charts, one
// panel per parameter or channel, in the house style of every figure the tools write.
#include <string>
#include <vector>

namespace mppi::sysid {

struct PlotSeries {
  std::vector<double> x, y;  // non-finite points break the line
  int colour = 0;  // index into the palette: 0 blue, 1 orange, 2 green, 3 red, 4 grey
  std::string label;
  bool dashed = false;
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
  std::vector<double> hlines;  // horizontal reference lines (e.g. the true value), grey dashed
  std::string hline_label = "true value";
  bool equal_axes = false;     // same scale on x and y (a path in the plane)
};

// Panels in a grid of `columns`; each panel at least panel_w x panel_h pixels; a title band on
// top; the legend in the first panel (the series mean the same in every panel). Throws
// mppi::Error if the file cannot be written.
void write_panels_png(const std::string& path, const std::string& title, const std::vector<PlotPanel>& panels,
                      int columns = 3, int panel_w = 420, int panel_h = 260);

}  // namespace mppi::sysid
