#include "plot/figure.hpp"

#include <cmath>

#include "base/error.hpp"

namespace mppi::plot {

namespace {

std::string quoted(const std::string& s) { return "'" + s + "'"; }

void check_points(const std::string& where, const std::vector<double>& x, const std::vector<double>& y,
                  const std::vector<double>* value = nullptr) {
  if (x.empty()) throw Error(where + " is empty");
  if (x.size() != y.size())
    throw Error(where + " has " + std::to_string(x.size()) + " x values but " + std::to_string(y.size()) + " y values");
  if (value && value->size() != x.size())
    throw Error(where + " has " + std::to_string(x.size()) + " points but " + std::to_string(value->size()) + " colour values");
  for (std::size_t i = 0; i < x.size(); ++i) {
    const char* bad = !std::isfinite(x[i]) ? "x" : !std::isfinite(y[i]) ? "y" : (value && !std::isfinite((*value)[i])) ? "colour value" : nullptr;
    if (bad)
      throw Error(where + ": point " + std::to_string(i) + " has a non-finite " + bad + " (" +
                  std::to_string(std::string(bad) == "x" ? x[i] : std::string(bad) == "y" ? y[i] : (*value)[i]) + ")");
  }
}

void check_limits(const std::string& where, const std::optional<Limits>& l, const char* axis) {
  if (l && !(std::isfinite(l->lo) && std::isfinite(l->hi) && l->hi > l->lo))
    throw Error(where + ": " + axis + " limits [" + std::to_string(l->lo) + ", " + std::to_string(l->hi) +
                "] are not an increasing finite range");
}

}  // namespace

std::vector<Series> finite_pieces(const Series& s) {
  std::vector<Series> pieces;
  bool open = false;
  for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
      open = false;
      continue;
    }
    if (!open) {
      Series piece = s;
      piece.x.clear();
      piece.y.clear();
      if (!pieces.empty()) piece.label.clear();
      pieces.push_back(piece);
      open = true;
    }
    pieces.back().x.push_back(s.x[i]);
    pieces.back().y.push_back(s.y[i]);
  }
  return pieces;
}

Figure::Figure(std::string title, int columns, int panel_width_px, int panel_height_px)
    : title_(std::move(title)), columns_(columns), panel_width_px_(panel_width_px), panel_height_px_(panel_height_px) {
  if (columns < 1) throw Error("figure " + quoted(title_) + ": columns must be >= 1");
  if (panel_width_px < 200 || panel_height_px < 150 || panel_width_px > 8000 || panel_height_px > 8000)
    throw Error("figure " + quoted(title_) + ": panel size " + std::to_string(panel_width_px) + " x " +
                std::to_string(panel_height_px) + " px is outside 200..8000 x 150..8000");
}

Panel& Figure::add(Panel panel) {
  panels_.push_back(std::move(panel));
  return panels_.back();
}

void Figure::validate() const {
  if (panels_.empty()) throw Error("figure " + quoted(title_) + " has no panels");
  for (std::size_t p = 0; p < panels_.size(); ++p) {
    const Panel& panel = panels_[p];
    const std::string where = "figure " + quoted(title_) + ", panel " + std::to_string(p) + " " + quoted(panel.title);
    for (std::size_t s = 0; s < panel.series.size(); ++s) {
      const Series& se = panel.series[s];
      check_points(where + ", series " + std::to_string(s) + " " + quoted(se.label), se.x, se.y);
      if (!(se.width_px >= 0) || (se.width_px == 0 && se.marker == Marker::kNone))
        throw Error(where + ", series " + std::to_string(s) + " " + quoted(se.label) + " has neither a line nor markers");
    }
    if (panel.trail) {
      const ColourTrail& t = *panel.trail;
      check_points(where + ", colour trail " + quoted(t.value_label), t.x, t.y, &t.value);
      if (!std::isfinite(t.value_min) || !std::isfinite(t.value_max) || t.value_max < t.value_min)
        throw Error(where + ", colour trail " + quoted(t.value_label) + ": colour scale [" + std::to_string(t.value_min) +
                    ", " + std::to_string(t.value_max) + "] is not a finite range");
    }
    for (const RefLine& r : panel.ref_lines)
      if (!std::isfinite(r.at)) throw Error(where + ": reference line " + quoted(r.label) + " is not at a finite value");
    check_limits(where, panel.x_limits, "x");
    check_limits(where, panel.y_limits, "y");
    if (panel.series.empty() && !panel.trail && !(panel.x_limits && panel.y_limits))
      throw Error(where + " has nothing to draw (no series, no trail) and no fixed limits");
  }
}

}  // namespace mppi::plot
