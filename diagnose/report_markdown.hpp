#pragma once
// report.md of `mppi-fit diagnose`: the verdict and headline first, then the screened values, the
// named and suspected effects, where the nominal model is wrong, every candidate, the held-out
// (and test) fit before and after, what is left, and the selection log.
#include <cstddef>
#include <string>

#include "diagnose/diagnose.hpp"

namespace mppi::diagnose {

// The values screened out of the recording (screen.hpp) that report.md and report.json list.
inline constexpr std::size_t kMaxListedFlags = 200;

// residual_horizon_s: the horizon of the locating residuals (the mismatch table's predictions).
std::string report_markdown(const PreparedRecording& d, const std::string& nominal_name, const DiagnoseOptions& o,
                            const DiagnoseResult& res, double residual_horizon_s);

}  // namespace mppi::diagnose
