#pragma once
// PNG of a simulated protocol run (sysid/protocol.hpp), drawn by mppi::plot: the driven path
// coloured by manoeuvre, and the true vx, vy and yaw rate over time in the same colours with the
// manoeuvre boundaries.
#include <string>

#include "sysid/protocol.hpp"

namespace mppi::sysid {

// Throws mppi::Error if the file cannot be written or the run has no truth rows.
void plot_protocol(const ProtocolRun& run, const std::string& png_path);

}  // namespace mppi::sysid
