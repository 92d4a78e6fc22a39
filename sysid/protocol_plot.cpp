#include "sysid/protocol_plot.hpp"

#include <algorithm>
#include <cmath>

#include "base/error.hpp"
#include "plot/figure.hpp"

namespace mppi::sysid {

namespace {

// Segments 1..5 in the palette's first colours, the validation lap (6) black.
plot::Rgb segment_colour(int segment) { return segment >= 6 ? plot::kBlack : plot::palette(segment - 1); }

// One series per run of rows in the same segment, labelled with the segment's name.
std::vector<plot::Series> by_segment(const std::vector<double>& x, const std::vector<double>& y,
                                     const std::vector<double>& seg, double width_px) {
  const auto& names = protocol_segment_names();
  std::vector<plot::Series> out;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const int s = std::clamp(static_cast<int>(seg[i]), 1, 6);
    if (out.empty() || (i > 0 && static_cast<int>(seg[i - 1]) != static_cast<int>(seg[i]))) {
      plot::Series piece;
      piece.colour = segment_colour(s);
      piece.width_px = width_px;
      piece.label = std::to_string(s) + " " + names[static_cast<std::size_t>(s - 1)];
      if (i > 0) {  // start where the previous piece ended, so the line is continuous
        piece.x.push_back(x[i - 1]);
        piece.y.push_back(y[i - 1]);
      }
      out.push_back(piece);
    }
    out.back().x.push_back(x[i]);
    out.back().y.push_back(y[i]);
  }
  return out;
}

}  // namespace

void plot_protocol(const ProtocolRun& run, const std::string& png_path) {
  const sim::Recording& tr = run.truth;
  if (tr.rows() < 2) throw Error(png_path + ": protocol run has no truth rows to plot");
  const auto& t = tr.column("t");
  const auto& seg = tr.column("segment");
  plot::Figure figure("simulated estimation protocol: full-vehicle plant, path and true velocities by manoeuvre", 2,
                      760, 420);
  plot::Panel path;
  path.title = "path";
  path.x_label = "x [m]";
  path.y_label = "y [m]";
  path.equal_scale = true;
  path.legend = plot::LegendPlace::kUpperLeft;
  path.series = by_segment(tr.column("x"), tr.column("y"), seg, 1.5);
  figure.add(path);
  struct Channel {
    const char* column;
    const char* title;
    const char* label;
  };
  for (const Channel& c : {Channel{"vx", "longitudinal speed", "vx [m/s]"}, Channel{"vy", "lateral speed", "vy [m/s]"},
                           Channel{"yaw_rate", "yaw rate", "yaw rate [rad/s]"}}) {
    plot::Panel p;
    p.title = c.title;
    p.x_label = "t [s]";
    p.y_label = c.label;
    p.legend = plot::LegendPlace::kNone;
    p.series = by_segment(t, tr.column(c.column), seg, 1.0);
    for (std::size_t i = 1; i < tr.rows(); ++i)
      if (seg[i] != seg[i - 1]) p.ref_lines.push_back({false, t[i], "", plot::kLightGrey, plot::Dash::kDotted, 1.0});
    figure.add(p);
  }
  figure.write_png(png_path);
}

}  // namespace mppi::sysid
