#include "sysid/estimation_plots.hpp"

#include <algorithm>
#include <cmath>

#include "plot/figure.hpp"

namespace mppi::sysid {

namespace {

plot::Rgb colour_of(int i) {
  switch (((i % 5) + 5) % 5) {
    case 0: return plot::palette(0);
    case 1: return plot::palette(1);
    case 2: return plot::palette(2);
    case 3: return plot::palette(3);
    default: return plot::kGrey;
  }
}

}  // namespace

void write_panels_png(const std::string& path, const std::string& title, const std::vector<PlotPanel>& panels,
                      int columns, int panel_w, int panel_h) {
  plot::Figure figure(title, columns, std::max(panel_w, 400), std::max(panel_h, 270));
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const PlotPanel& in = panels[i];
    plot::Panel p;
    p.title = in.title;
    p.x_label = in.x_label;
    p.y_label = in.y_label;
    p.equal_scale = in.equal_axes;
    p.legend = i == 0 ? plot::LegendPlace::kUpperRight : plot::LegendPlace::kNone;
    for (const PlotSeries& s : in.series) {
      plot::Series out;
      out.x = s.x;
      out.y = s.y;
      out.label = s.label;
      out.colour = colour_of(s.colour);
      out.dash = s.dashed ? plot::Dash::kDashed : plot::Dash::kSolid;
      for (plot::Series& piece : plot::finite_pieces(out)) p.series.push_back(std::move(piece));
    }
    for (double h : in.hlines)
      if (std::isfinite(h)) p.ref_lines.push_back({true, h, in.hline_label, plot::kGrey, plot::Dash::kDashed, 1.2});
    figure.add(p);
  }
  figure.write_png(path);
}

}  // namespace mppi::sysid
