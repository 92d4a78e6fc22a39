#pragma once
// A Figure as JSON: what it shows (series, trails, reference lines, colours) and how it is
// laid out (each panel's limits and tick step), for reports and interactive copies.
#include <nlohmann/json.hpp>

#include "plot/figure.hpp"

namespace mppi::plot {

// Validates the figure (mppi::Error) like write_png.
nlohmann::ordered_json figure_to_json(const Figure& figure);

}  // namespace mppi::plot
