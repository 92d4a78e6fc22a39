#pragma once
// Where everything of a Figure goes, in pixels (row 0 at the top), and the axis ranges each
// panel is drawn with. Shared by the PNG renderer and the JSON / HTML copy so both show the same
// limits and ticks.
#include <string>
#include <vector>

#include "plot/figure.hpp"
#include "plot/ticks.hpp"

namespace mppi::plot {

struct PixelRect {
  double left = 0, top = 0, width = 0, height = 0;
  double right() const { return left + width; }
  double bottom() const { return top + height; }
};

struct TextBlock {
  std::vector<std::string> lines;
  double size_px = 14;    // font size (em height)
  double line_px = 18;    // line pitch
};

struct PanelLayout {
  PixelRect cell, axes;
  NiceAxis x, y;          // limits and tick step
  TextBlock title;
  bool has_colour_bar = false;
  PixelRect colour_bar;
  NiceAxis colour_axis;   // the colour scale: [value_min, value_max] and its ticks
};

struct FigureLayout {
  int width_px = 0, height_px = 0;
  TextBlock title;
  std::vector<PanelLayout> panels;
  // Pixel (column, row) of a data point in panel p (fractional; row grows downwards).
  std::pair<double, double> to_pixel(std::size_t p, double x, double y) const;
};

// Font sizes of the house style, in pixels.
inline constexpr double kFigureTitlePx = 17, kPanelTitlePx = 14, kLabelPx = 13, kTickPx = 12, kLegendPx = 12;

// Estimated width of `text` at font size size_px (DejaVu Sans proportions).
double text_width_px(const std::string& text, double size_px);
// Lines of at most width_px, broken at " | ", ", " or spaces, and the font size (shrunk from
// size_px down to 70 % if a word alone would not fit).
TextBlock fit_text(const std::string& text, double width_px, double size_px, int max_lines = 3);

// Validates the figure (mppi::Error on bad data) and lays it out.
FigureLayout layout_figure(const Figure& figure);

}  // namespace mppi::plot
