#pragma once
// The page's picture of a track: its boundaries, barriers, centreline and cost map (bounds and
// a downsampled grid of the cost, one byte a cell: 0 = cost 0, 255 = cost >= 2), as JSON.
#include <string>

namespace mppi::ocs {

// A built-in track by name (sim::Track::load) with its cost map; cells at most max_cells_per_side
// a side. Throws mppi::Error for an unknown track or a bad cost-map file.
std::string track_json(const std::string& track_name, bool clockwise, int max_cells_per_side = 400);

}  // namespace mppi::ocs
