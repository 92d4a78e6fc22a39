#pragma once
// A corrected model against its nominal model on rows of a recording: the multi-step errors of
// both (one step, then the given horizons), as the diagnosis reports its held-out and test parts
// and mppi-fit evaluate reports any recording; and those errors as report.json writes them.
#include <vector>

#include <nlohmann/json.hpp>

#include "diagnose/data.hpp"
#include "diagnose/model_family.hpp"
#include "diagnose/replay.hpp"

namespace mppi::diagnose {

struct ModelComparison {
  std::vector<HorizonMetrics> nominal, corrected;       // one-step first, then the horizons
  double headline_nominal = 0, headline_corrected = 0;  // normalised RMSE at the headline horizon
  double reduction = 0;                                 // 1 - corrected / nominal at the headline
};

// Both models replayed from the rows of `mask` (1 = scored) at d.dt_s and `horizons_s`.
ModelComparison compare_models(const ReplayModel& nominal, const ReplayModel& corrected, const PreparedRecording& d,
                               const std::vector<char>& mask, const std::vector<double>& horizons_s,
                               double headline_horizon_s, const ReplayOptions& o);

// The entry of `ms` at horizon h [s], or nullptr.
const HorizonMetrics* at_horizon(const std::vector<HorizonMetrics>& ms, double h);

// report.json's form of a list of horizon metrics (non-finite values as null).
nlohmann::json horizon_metrics_json(const std::vector<HorizonMetrics>& ms);

}  // namespace mppi::diagnose
