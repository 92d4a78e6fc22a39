#pragma once
// A recording (docs/RECORDING_FORMAT.md: the simulator's log.csv, converted real data) as the
// JSON the replay page reads: its metadata and the columns it draws, every `stride`-th row so
// that at most max_rows rows go to the page. Missing values are null.
#include <string>

#include "sim/recording.hpp"

namespace mppi::ocs {

std::string recording_json(const sim::Recording& recording, const std::string& source, std::size_t max_rows = 20000);

}  // namespace mppi::ocs
