#include "plot/figure_from_json.hpp"

#include <string>

#include "base/error.hpp"

namespace mppi::plot {

namespace {

using json = nlohmann::json;

template <class T>
T value_or(const json& j, const char* key, T fallback, const std::string& where) {
  if (!j.contains(key)) return fallback;
  try {
    return j.at(key).get<T>();
  } catch (const json::exception& e) {
    throw Error("figure JSON: " + where + "." + key + ": " + e.what());
  }
}

Rgb colour_of(const json& j, const char* key, Rgb fallback, const std::string& where) {
  const std::string hex = value_or<std::string>(j, key, "", where);
  if (hex.empty()) return fallback;
  if (hex.size() != 7 || hex[0] != '#' || hex.find_first_not_of("0123456789abcdefABCDEF", 1) != std::string::npos)
    throw Error("figure JSON: " + where + "." + key + ": '" + hex + "' is not a colour #rrggbb");
  const auto byte = [&](int i) { return static_cast<std::uint8_t>(std::stoi(hex.substr(1 + 2 * i, 2), nullptr, 16)); };
  return {byte(0), byte(1), byte(2)};
}

Dash dash_of(const json& j, Dash fallback, const std::string& where) {
  const std::string id = value_or<std::string>(j, "dash", "", where);
  if (id.empty()) return fallback;
  if (id == "solid") return Dash::kSolid;
  if (id == "dashed") return Dash::kDashed;
  if (id == "dotted") return Dash::kDotted;
  throw Error("figure JSON: " + where + ".dash: '" + id + "' (valid: solid, dashed, dotted)");
}

Marker marker_of(const json& j, const std::string& where) {
  const std::string id = value_or<std::string>(j, "marker", "none", where);
  if (id == "none") return Marker::kNone;
  if (id == "circle") return Marker::kCircle;
  if (id == "cross") return Marker::kCross;
  if (id == "square") return Marker::kSquare;
  throw Error("figure JSON: " + where + ".marker: '" + id + "' (valid: none, circle, cross, square)");
}

LegendPlace legend_of(const json& j, const std::string& where) {
  const std::string id = value_or<std::string>(j, "legend", "upper_right", where);
  if (id == "upper_right") return LegendPlace::kUpperRight;
  if (id == "upper_left") return LegendPlace::kUpperLeft;
  if (id == "lower_right") return LegendPlace::kLowerRight;
  if (id == "lower_left") return LegendPlace::kLowerLeft;
  if (id == "none") return LegendPlace::kNone;
  throw Error("figure JSON: " + where + ".legend: '" + id +
              "' (valid: upper_right, upper_left, lower_right, lower_left, none)");
}

std::vector<double> numbers(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) throw Error("figure JSON: " + where + " has no '" + key + "'");
  return value_or<std::vector<double>>(j, key, {}, where);
}

std::optional<Limits> limits_of(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) return std::nullopt;
  const std::string at = where + "." + key;
  return Limits{value_or<double>(j.at(key), "lo", 0.0, at), value_or<double>(j.at(key), "hi", 1.0, at)};
}

Series series_of(const json& j, const std::string& where) {
  Series s;
  s.x = numbers(j, "x", where);
  s.y = numbers(j, "y", where);
  s.label = value_or<std::string>(j, "label", "", where);
  s.colour = colour_of(j, "colour", s.colour, where);
  s.width_px = value_or<double>(j, "width_px", s.width_px, where);
  s.dash = dash_of(j, s.dash, where);
  s.marker = marker_of(j, where);
  s.marker_px = value_or<double>(j, "marker_px", s.marker_px, where);
  return s;
}

RefLine ref_line_of(const json& j, const std::string& where) {
  RefLine r;
  r.horizontal = value_or<bool>(j, "horizontal", r.horizontal, where);
  r.at = value_or<double>(j, "at", r.at, where);
  r.label = value_or<std::string>(j, "label", "", where);
  r.colour = colour_of(j, "colour", r.colour, where);
  r.dash = dash_of(j, r.dash, where);
  r.width_px = value_or<double>(j, "width_px", r.width_px, where);
  return r;
}

ColourTrail trail_of(const json& j, const std::string& where) {
  ColourTrail t;
  t.x = numbers(j, "x", where);
  t.y = numbers(j, "y", where);
  t.value = numbers(j, "value", where);
  t.value_label = value_or<std::string>(j, "value_label", "", where);
  const std::string map = value_or<std::string>(j, "map", "turbo", where);
  if (map != "turbo" && map != "viridis")
    throw Error("figure JSON: " + where + ".map: '" + map + "' (valid: turbo, viridis)");
  t.map = map == "viridis" ? ColourMapName::kViridis : ColourMapName::kTurbo;
  if (const std::optional<Limits> scale = limits_of(j, "colour_axis", where)) {
    t.value_min = scale->lo;
    t.value_max = scale->hi;
  }
  t.width_px = value_or<double>(j, "width_px", t.width_px, where);
  return t;
}

Panel panel_of(const json& j, const std::string& where) {
  Panel p;
  p.title = value_or<std::string>(j, "title", "", where);
  p.x_label = value_or<std::string>(j, "x_label", "", where);
  p.y_label = value_or<std::string>(j, "y_label", "", where);
  p.x_limits = limits_of(j, "x_axis", where);
  p.y_limits = limits_of(j, "y_axis", where);
  p.equal_scale = value_or<bool>(j, "equal_scale", false, where);
  p.right_axis = value_or<bool>(j, "right_axis", false, where);
  p.legend = legend_of(j, where);
  if (j.contains("series"))
    for (std::size_t i = 0; i < j.at("series").size(); ++i)
      p.series.push_back(series_of(j.at("series").at(i), where + ".series[" + std::to_string(i) + "]"));
  if (j.contains("ref_lines"))
    for (std::size_t i = 0; i < j.at("ref_lines").size(); ++i)
      p.ref_lines.push_back(ref_line_of(j.at("ref_lines").at(i), where + ".ref_lines[" + std::to_string(i) + "]"));
  if (j.contains("trail") && !j.at("trail").is_null()) p.trail = trail_of(j.at("trail"), where + ".trail");
  return p;
}

}  // namespace

Figure figure_from_json(const json& j) {
  if (!j.is_object() || !j.contains("panels") || !j.at("panels").is_array())
    throw Error("figure JSON: expected an object with a 'panels' array");
  Figure figure(value_or<std::string>(j, "title", "", "figure"), value_or<int>(j, "columns", 1, "figure"),
                value_or<int>(j, "panel_width_px", 640, "figure"), value_or<int>(j, "panel_height_px", 420, "figure"));
  const json& panels = j.at("panels");
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const std::string where = "panels[" + std::to_string(i) + "]";
    try {
      figure.add(panel_of(panels.at(i), where));
    } catch (const json::exception& e) {  // a list that is not a list, an entry not an object
      throw Error("figure JSON: " + where + ": " + e.what());
    }
  }
  figure.validate();
  return figure;
}

}  // namespace mppi::plot
