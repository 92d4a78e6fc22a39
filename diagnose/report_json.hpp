#pragma once
// report.json of `mppi-fit diagnose` (its keys: docs/DIAGNOSE.md), without the figures, which the
// caller adds when it draws them.
#include <string>

#include <nlohmann/json.hpp>

#include "diagnose/diagnose.hpp"

namespace mppi::diagnose {

nlohmann::ordered_json report_json(const PreparedRecording& d, const std::string& nominal_name, const DiagnoseOptions& o,
                                   const DiagnoseResult& res);

}  // namespace mppi::diagnose
