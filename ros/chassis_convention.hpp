#pragma once
// The steering sign on AutoRally's chassis messages. AutoRally's chassisCommand and chassisState
// steer positive to the RIGHT (+1 full right: the convention its network was trained in, see
// dynamics/autorally_nn.hpp); the library's controls steer positive to the LEFT
// (dynamics/single_track.hpp). Every steering value that crosses a chassis message goes through
// these two, so that the nodes drive AutoRally's own chassis and read its bags the right way round
// (the rosbag import's default steer_sign, docs/ROSBAG.md, is the same flip).
namespace mppi::ros {

inline double chassis_steering_from_library(double steer) { return -steer; }
inline double library_steer_from_chassis(double steering) { return -steering; }

}  // namespace mppi::ros
