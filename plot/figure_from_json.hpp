#pragma once
// A Figure read back from its JSON (plot/figure_json.hpp), so that a script can describe a
// figure as data and have it drawn in the house style (mppi-plot, apps/mppi_plot.cpp).
#include <nlohmann/json.hpp>

#include "plot/figure.hpp"

namespace mppi::plot {

// The keys of figure_to_json. Required: "panels" (an array) and each series' "x" and "y";
// every other key takes the Figure / Panel / Series default. A panel's "x_axis" / "y_axis"
// ({"lo", "hi"}; "step" is ignored) become fixed limits; a trail's "colour_axis" its colour
// scale. Colours are "#rrggbb". Throws mppi::Error naming the key for a missing or malformed
// value, and for data the figure refuses (Figure::validate).
Figure figure_from_json(const nlohmann::json& j);

}  // namespace mppi::plot
