#include "sim/track_plot.hpp"

#include <algorithm>
#include <cmath>

#include "base/error.hpp"
#include "plot/layout.hpp"

namespace mppi::sim {

namespace {

constexpr plot::Rgb kBarrierColour{70, 70, 70};
constexpr plot::Rgb kBoundaryColour{0, 0, 0};
constexpr plot::Rgb kCentreColour{170, 170, 170};
constexpr plot::Rgb kStartColour{0, 140, 0};
constexpr plot::Rgb kCrashColour{230, 0, 0};

plot::Series closed_line(const Polyline& line, plot::Rgb colour, double width_px, const std::string& label) {
  plot::Series s;
  for (const Vec2& p : line) {
    s.x.push_back(p.x);
    s.y.push_back(p.y);
  }
  if (!line.empty()) {
    s.x.push_back(line.front().x);
    s.y.push_back(line.front().y);
  }
  s.colour = colour;
  s.width_px = width_px;
  s.label = label;
  return s;
}

plot::Series segment(double x0, double y0, double x1, double y1, plot::Rgb colour, double width_px,
                     const std::string& label = "") {
  plot::Series s;
  s.x = {x0, x1};
  s.y = {y0, y1};
  s.colour = colour;
  s.width_px = width_px;
  s.label = label;
  return s;
}

}  // namespace

std::array<std::uint8_t, 3> speed_colour_rgb(double v, double v_min, double v_max) {
  const plot::Rgb c = plot::colour_for_value(plot::ColourMapName::kTurbo, v, v_min, v_max);
  return {c.r, c.g, c.b};
}

plot::Figure track_run_figure(const Track& track, const std::vector<PathSample>& path,
                              const std::vector<std::pair<float, float>>& crash_points,
                              const std::string& title, const PlotOptions& options) {
  const Bounds b = track.bounds();
  const double aspect = std::max(b.x_max - b.x_min, 1e-3) / std::max(b.y_max - b.y_min, 1e-3);
  const bool has_path = !path.empty();
  plot::Figure figure(title, 1, options.width_px,
                      plot::Figure::panel_height_for_aspect(options.width_px, aspect, has_path));
  plot::Panel panel;
  panel.x_label = "x [m]";
  panel.y_label = "y [m]";
  panel.equal_scale = true;
  panel.legend = plot::LegendPlace::kLowerLeft;
  // Track: barrier pipes (their width set below, once the scale is known), else the boundaries.
  if (track.has_barriers()) {
    for (const Barrier& bar : track.barriers())
      panel.series.push_back(closed_line(bar.centre, kBarrierColour, 2.0, "barrier"));
  } else {
    panel.series.push_back(closed_line(track.inner(), kBoundaryColour, 2.0, "track edge"));
    panel.series.push_back(closed_line(track.outer(), kBoundaryColour, 2.0, "track edge"));
  }
  plot::Series centre = closed_line(track.centreline(), kCentreColour, 1.0, "centreline");
  centre.dash = plot::Dash::kDashed;
  panel.series.push_back(centre);
  // Start: a line across the track and an arrow along the driving direction.
  {
    const Pose2 s = track.start_pose();
    const double cy = std::cos(s.yaw_rad), sy = std::sin(s.yaw_rad);
    panel.series.push_back(segment(s.x_m - 1.2 * sy, s.y_m + 1.2 * cy, s.x_m + 1.2 * sy, s.y_m - 1.2 * cy,
                                   kStartColour, 2.5, "start, direction"));
    const double tip_x = s.x_m + 2.0 * cy, tip_y = s.y_m + 2.0 * sy;
    panel.series.push_back(segment(s.x_m, s.y_m, tip_x, tip_y, kStartColour, 2.5));
    for (double side : {-1.0, 1.0}) {
      const double a = s.yaw_rad + M_PI + side * 0.5;
      panel.series.push_back(segment(tip_x, tip_y, tip_x + 0.6 * std::cos(a), tip_y + 0.6 * std::sin(a), kStartColour, 2.5));
    }
  }
  if (has_path) {
    plot::ColourTrail trail;
    trail.value_label = options.quantity + " [" + options.unit + "]";
    for (const PathSample& p : path) {
      trail.x.push_back(p.x_m);
      trail.y.push_back(p.y_m);
      trail.value.push_back(p.speed_mps);
    }
    if (options.speed_max_mps > options.speed_min_mps) {
      trail.value_min = options.speed_min_mps;
      trail.value_max = options.speed_max_mps;
    }
    panel.trail = trail;
  }
  if (!crash_points.empty()) {
    plot::Series crashes;
    for (const auto& [x, y] : crash_points) {
      crashes.x.push_back(x);
      crashes.y.push_back(y);
    }
    crashes.width_px = 0;
    crashes.marker = plot::Marker::kCross;
    crashes.marker_px = 16;
    crashes.colour = kCrashColour;
    crashes.label = "crash";
    panel.series.push_back(crashes);
  }
  figure.add(panel);
  // Barrier pipes drawn at their real width.
  if (track.has_barriers()) {
    const plot::FigureLayout layout = plot::layout_figure(figure);
    const plot::PanelLayout& l = layout.panels[0];
    const double px_per_m = l.axes.width / (l.x.hi - l.x.lo);
    plot::Figure sized(title, 1, figure.panel_width_px(), figure.panel_height_px());
    plot::Panel p = figure.panels()[0];
    for (std::size_t i = 0; i < track.barriers().size(); ++i)
      p.series[i].width_px = std::max(2.0, 2.0 * track.barriers()[i].radius_m * px_per_m);
    sized.add(p);
    return sized;
  }
  return figure;
}

void plot_track_run(const std::string& png_path, const Track& track, const std::vector<PathSample>& path,
                    const std::vector<std::pair<float, float>>& crash_points, const std::string& title,
                    const PlotOptions& options) {
  track_run_figure(track, path, crash_points, title, options).write_png(png_path);
}

}  // namespace mppi::sim
