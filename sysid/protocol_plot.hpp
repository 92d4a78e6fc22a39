#pragma once
// PNG of a simulated protocol run (sysid/protocol.hpp): the driven path coloured by manoeuvre
// (left) and the true vx, vy and yaw rate over time with the manoeuvre boundaries (right).
#include <string>

#include "sysid/protocol.hpp"

namespace mppi::sysid {

// Throws mppi::Error if the file cannot be written or the run has no truth rows.
void plot_protocol(const ProtocolRun& run, const std::string& png_path);

}  // namespace mppi::sysid
