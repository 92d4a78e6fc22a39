#include "diagnose/model_comparison.hpp"

#include <cmath>

namespace mppi::diagnose {

ModelComparison compare_models(const ReplayModel& nominal, const ReplayModel& corrected, const PreparedRecording& d,
                               const std::vector<char>& mask, const std::vector<double>& horizons_s,
                               double headline_horizon_s, const ReplayOptions& o) {
  std::vector<double> hs = {d.dt_s};
  hs.insert(hs.end(), horizons_s.begin(), horizons_s.end());
  ModelComparison c;
  c.nominal = horizon_metrics(nominal, d, mask, hs, 5, o);
  c.corrected = horizon_metrics(corrected, d, mask, hs, 5, o);
  const HorizonMetrics* before = at_horizon(c.nominal, headline_horizon_s);
  const HorizonMetrics* after = at_horizon(c.corrected, headline_horizon_s);
  if (before && after) {
    c.headline_nominal = before->normalized_rmse;
    c.headline_corrected = after->normalized_rmse;
    c.reduction = c.headline_nominal > 0 ? 1.0 - c.headline_corrected / c.headline_nominal : 0.0;
  }
  return c;
}

const HorizonMetrics* at_horizon(const std::vector<HorizonMetrics>& ms, double h) {
  for (const auto& m : ms)
    if (std::abs(m.horizon_s - h) < 1e-9) return &m;
  return nullptr;
}

nlohmann::json horizon_metrics_json(const std::vector<HorizonMetrics>& ms) {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json out = nlohmann::json::array();
  for (const auto& m : ms) {
    nlohmann::json j;
    j["horizon_s"] = m.horizon_s;
    j["starts"] = m.starts;
    for (int c = 0; c < kChannels; ++c) {
      j["rmse"][kChannelNames[c]] = num(m.rmse[c]);
      j["fit_percent"][kChannelNames[c]] = num(m.fit_percent[c]);
    }
    j["position_rmse_m"] = num(m.position_rmse_m);
    j["normalized_rmse"] = num(m.normalized_rmse);
    out.push_back(j);
  }
  return out;
}

}  // namespace mppi::diagnose
