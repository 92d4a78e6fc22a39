#include "plot/figure_json.hpp"

#include "plot/layout.hpp"

namespace mppi::plot {

namespace {

using json = nlohmann::ordered_json;

const char* dash_id(Dash d) { return d == Dash::kDashed ? "dashed" : d == Dash::kDotted ? "dotted" : "solid"; }
const char* marker_id(Marker m) {
  return m == Marker::kCircle ? "circle" : m == Marker::kCross ? "cross" : m == Marker::kSquare ? "square" : "none";
}
const char* legend_id(LegendPlace p) {
  switch (p) {
    case LegendPlace::kUpperRight: return "upper_right";
    case LegendPlace::kUpperLeft: return "upper_left";
    case LegendPlace::kLowerRight: return "lower_right";
    case LegendPlace::kLowerLeft: return "lower_left";
    case LegendPlace::kNone: return "none";
  }
  return "none";
}

json axis(const NiceAxis& a) { return {{"lo", a.lo}, {"hi", a.hi}, {"step", a.step}}; }

}  // namespace

json figure_to_json(const Figure& figure) {
  const FigureLayout layout = layout_figure(figure);
  json panels = json::array();
  for (std::size_t p = 0; p < figure.panels().size(); ++p) {
    const Panel& panel = figure.panels()[p];
    const PanelLayout& l = layout.panels[p];
    json jp;
    jp["title"] = panel.title;
    jp["x_label"] = panel.x_label;
    jp["y_label"] = panel.y_label;
    jp["x_axis"] = axis(l.x);
    jp["y_axis"] = axis(l.y);
    jp["equal_scale"] = panel.equal_scale;
    jp["right_axis"] = panel.right_axis;
    jp["legend"] = legend_id(panel.legend);
    json series = json::array();
    for (const Series& s : panel.series)
      series.push_back({{"label", s.label}, {"colour", to_hex(s.colour)}, {"width_px", s.width_px},
                        {"dash", dash_id(s.dash)}, {"marker", marker_id(s.marker)}, {"marker_px", s.marker_px},
                        {"x", s.x}, {"y", s.y}});
    jp["series"] = series;
    json refs = json::array();
    for (const RefLine& r : panel.ref_lines)
      refs.push_back({{"horizontal", r.horizontal}, {"at", r.at}, {"label", r.label}, {"colour", to_hex(r.colour)},
                      {"dash", dash_id(r.dash)}, {"width_px", r.width_px}});
    jp["ref_lines"] = refs;
    if (panel.trail) {
      const ColourTrail& t = *panel.trail;
      json colours = json::array();
      for (int i = 0; i < 256; ++i) colours.push_back(to_hex(colour_map_rgb(t.map, i / 255.0)));
      jp["trail"] = {{"value_label", t.value_label}, {"map", colour_map_id(t.map)}, {"colour_axis", axis(l.colour_axis)},
                     {"width_px", t.width_px}, {"x", t.x}, {"y", t.y}, {"value", t.value}, {"colours", colours}};
    }
    panels.push_back(jp);
  }
  return {{"title", figure.title()}, {"columns", std::min<int>(figure.columns(), static_cast<int>(figure.panels().size()))},
          {"panel_width_px", figure.panel_width_px()}, {"panel_height_px", figure.panel_height_px()}, {"panels", panels}};
}

}  // namespace mppi::plot
