#include "ocs/track_json.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "mppi/cost_map.hpp"
#include "sim/track.hpp"

namespace mppi::ocs {
namespace {

// [x0, y0, x1, y1, ...] every `spacing_m` or so, in centimetres resolution.
nlohmann::json polyline_json(const sim::Polyline& line, double spacing_m) {
  nlohmann::json out = nlohmann::json::array();
  double since = spacing_m;
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (i > 0) since += std::hypot(line[i].x - line[i - 1].x, line[i].y - line[i - 1].y);
    if (since < spacing_m && i + 1 < line.size()) continue;
    out.push_back(std::round(line[i].x * 100.0) / 100.0);
    out.push_back(std::round(line[i].y * 100.0) / 100.0);
    since = 0.0;
  }
  return out;
}

}  // namespace

std::string track_json(const std::string& track_name, bool clockwise, int max_cells_per_side) {
  sim::TrackOptions options;
  options.direction = clockwise ? sim::Direction::kClockwise : sim::Direction::kCounterClockwise;
  const sim::Track track = sim::Track::load(track_name, options);
  const CostMap map = CostMap::load_npz(track.costmap_path());
  nlohmann::json j;
  j["name"] = track.name();
  j["inner"] = polyline_json(track.inner(), 0.2);
  j["outer"] = polyline_json(track.outer(), 0.2);
  j["centreline"] = polyline_json(track.centreline(), 0.5);
  nlohmann::json barriers = nlohmann::json::array();
  for (const sim::Barrier& b : track.barriers())
    barriers.push_back({{"name", b.name}, {"radius_m", b.radius_m}, {"centre", polyline_json(b.centre, 0.2)}});
  j["barriers"] = std::move(barriers);
  const sim::Bounds b = track.bounds();
  j["bounds"] = {b.x_min, b.x_max, b.y_min, b.y_max};
  // Cost map: every `step`-th pixel (row 0 at y_min), each cell the maximum of its block.
  const int step = std::max(1, (std::max(map.width(), map.height()) + max_cells_per_side - 1) / max_cells_per_side);
  const int cols = (map.width() + step - 1) / step, rows = (map.height() + step - 1) / step;
  std::string cells(static_cast<std::size_t>(cols) * rows, '\0');
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      float v = 0.f;
      for (int rr = r * step; rr < std::min(map.height(), (r + 1) * step); ++rr)
        for (int cc = c * step; cc < std::min(map.width(), (c + 1) * step); ++cc) v = std::max(v, map.at(rr, cc));
      cells[static_cast<std::size_t>(r) * cols + c] = static_cast<char>(std::lround(std::clamp(v / 2.f, 0.f, 1.f) * 255.f));
    }
  nlohmann::json grid = nlohmann::json::array();
  for (char ch : cells) grid.push_back(static_cast<unsigned char>(ch));
  j["costmap"] = {{"x_min", map.x_min_m()}, {"x_max", map.x_max_m()}, {"y_min", map.y_min_m()},
                  {"y_max", map.y_max_m()}, {"cols", cols}, {"rows", rows}, {"cells", std::move(grid)}};
  return j.dump();
}

}  // namespace mppi::ocs
