#pragma once
// A LiveFrame as the JSON the page reads (docs/OCS.md lists the fields), with the paths
// predicted from the frame's control sequences by the controller's model.
#include <string>
#include <vector>

#include "chassis/priorities.hpp"
#include "ocs/live_frame.hpp"
#include "sim/step_observer.hpp"

namespace mppi::ocs {

// Name of an Arbiter commander index: a controller of `priorities`, or runstop / watchdog / none.
std::string commander_name(int commander, const std::vector<chassis::PriorityEntry>& priorities);

// `paused`: the operator has paused the simulation. Paths are kept at every `path_stride`-th
// time step (and the last), in metres with millimetre resolution.
std::string frame_json(const LiveFrame& frame, const sim::PathPredictor& predictor,
                       const std::vector<chassis::PriorityEntry>& priorities, bool paused,
                       int path_stride = 2);

}  // namespace mppi::ocs
