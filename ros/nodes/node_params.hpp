#pragma once
// Reading the nodes' private parameters (C++17, header-only).
#include <stdexcept>
#include <string>

#include <ros/node_handle.h>

namespace mppi::ros {

// A private parameter, if set; one of another type is refused by name (not silently ignored).
template <class T>
void read_param(::ros::NodeHandle& nh, const std::string& name, T& value) {
  if (nh.hasParam(name) && !nh.getParam(name, value))
    throw std::runtime_error("parameter " + nh.resolveName(name) + " has the wrong type");
}

}  // namespace mppi::ros
