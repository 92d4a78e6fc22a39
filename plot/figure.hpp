#pragma once
// A figure of one or more panels drawn by PLplot (plot/render_png.cpp) in one house style:
// white background, light grid at the major ticks, "nice" tick values (plot/ticks.hpp), axis
// labels with units, a legend, titles that wrap or shrink to fit. A panel holds line / scatter
// series, reference lines and at most one trail coloured by a value with its colour bar.
// Invalid data (empty series, NaN or infinite values, mismatched lengths) is refused with an
// mppi::Error naming the figure, the panel and the series.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "plot/colour_map.hpp"

namespace mppi::plot {

enum class Dash { kSolid, kDashed, kDotted };
enum class Marker { kNone, kCircle, kCross, kSquare };

// A polyline (width_px > 0) and/or markers at its points (scatter: width_px = 0).
struct Series {
  std::vector<double> x, y;
  std::string label;  // legend entry; empty = not in the legend
  Rgb colour = palette(0);
  double width_px = 1.5;
  Dash dash = Dash::kSolid;
  Marker marker = Marker::kNone;
  double marker_px = 7.0;  // marker size (diameter / cross size)
};

// A path coloured point by point by `value` through a colour map, with a colour bar.
struct ColourTrail {
  std::vector<double> x, y, value;
  std::string value_label;  // colour bar label with unit, e.g. "speed [m/s]"
  ColourMapName map = ColourMapName::kTurbo;
  double value_min = 0.0, value_max = 0.0;  // colour scale; min == max = the data's range
  double width_px = 3.0;
};

// A horizontal (y = at) or vertical (x = at) line across the panel.
struct RefLine {
  bool horizontal = true;
  double at = 0.0;
  std::string label;  // legend entry; empty = none
  Rgb colour = kGrey;
  Dash dash = Dash::kDashed;
  double width_px = 1.0;
};

struct Limits {
  double lo = 0.0, hi = 1.0;
};

enum class LegendPlace { kUpperRight, kUpperLeft, kLowerRight, kLowerLeft, kNone };

struct Panel {
  std::string title;
  std::string x_label, y_label;  // with units, e.g. "t [s]"
  std::vector<Series> series;
  std::optional<ColourTrail> trail;
  std::vector<RefLine> ref_lines;
  std::optional<Limits> x_limits, y_limits;  // fixed limits; unset = nice limits covering the data
  bool equal_scale = false;  // one data unit is as long on x as on y (maps, paths in the plane)
  bool right_axis = false;   // a twin y axis on the right; it always has the left axis' limits
  LegendPlace legend = LegendPlace::kUpperRight;
};

// The limits and ticks a panel was drawn with (for tests and interactive copies).
struct AxisRange {
  double lo = 0.0, hi = 1.0, step = 1.0;
};

// The runs of finite points of `s` as separate series (NaN or infinite values mark gaps), the
// legend label on the first; empty if no point is finite.
std::vector<Series> finite_pieces(const Series& s);

class Figure {
 public:
  // Panels fill a grid `columns` wide, each panel cell panel_width_px x panel_height_px; the
  // figure title sits in a band above the grid.
  Figure(std::string title, int columns = 1, int panel_width_px = 640, int panel_height_px = 420);

  Panel& add(Panel panel);
  const std::vector<Panel>& panels() const { return panels_; }
  const std::string& title() const { return title_; }
  int columns() const { return columns_; }
  int panel_width_px() const { return panel_width_px_; }
  int panel_height_px() const { return panel_height_px_; }

  // The cell height that gives an equal-scale panel of data aspect (width / height) with no
  // empty band, for a cell panel_width_px wide.
  static int panel_height_for_aspect(int panel_width_px, double data_width_over_height, bool colour_bar);

  // Throws mppi::Error for invalid data (see above) or an unwritable file.
  void write_png(const std::string& path) const;

  // Checks the data; throws mppi::Error naming the first problem.
  void validate() const;

 private:
  std::string title_;
  int columns_, panel_width_px_, panel_height_px_;
  std::vector<Panel> panels_;
};

}  // namespace mppi::plot
