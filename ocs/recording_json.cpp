#include "ocs/recording_json.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

namespace mppi::ocs {

std::string recording_json(const sim::Recording& recording, const std::string& source, std::size_t max_rows) {
  nlohmann::json j;
  j["source"] = source;
  j["metadata"] = recording.metadata;
  j["rows"] = recording.rows();
  const std::size_t stride = std::max<std::size_t>(1, (recording.rows() + max_rows - 1) / std::max<std::size_t>(1, max_rows));
  j["stride"] = stride;
  // The common columns, and the simulator's diagnostics when present.
  const char* wanted[] = {"t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle",
                          "optimizer_ms", "effective_sample_size", "lap", "progress_m"};
  nlohmann::json columns = nlohmann::json::object();
  for (const char* name : wanted) {
    if (!recording.has_column(name)) continue;
    const std::vector<double>& v = recording.column(name);
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t r = 0; r < v.size(); r += stride) {
      if (std::isfinite(v[r])) out.push_back(std::round(v[r] * 10000.0) / 10000.0);
      else out.push_back(nullptr);
    }
    columns[name] = std::move(out);
  }
  j["columns"] = std::move(columns);
  return j.dump();
}

}  // namespace mppi::ocs
