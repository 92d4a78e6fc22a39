#include "ros/safety_monitor.hpp"

#include <cmath>

namespace mppi::ros {

bool SafetySettings::is_valid(std::string* why) const {
  if (!(pose_timeout_s > 0.0) || !std::isfinite(pose_timeout_s)) {
    if (why) *why = "pose_timeout_s must be > 0 and finite";
    return false;
  }
  if (!(runstop_timeout_s > 0.0) || !std::isfinite(runstop_timeout_s)) {
    if (why) *why = "runstop_timeout_s must be > 0 and finite";
    return false;
  }
  return true;
}

bool SafetyMonitor::motion_allowed(double now_s) const {
  if (!motion_enabled_ || !page_motion_allowed_) return false;
  if (settings_.require_runstop)
    return last_runstop_s_ && now_s - *last_runstop_s_ <= settings_.runstop_timeout_s;
  return true;
}

NodeStatus SafetyMonitor::status(double now_s) const {
  NodeStatus s;
  if (!last_pose_s_) {
    s.level = StatusLevel::kWarning;
    s.info = "No pose estimates received.";
  } else if (pose_stale(now_s)) {
    s.level = StatusLevel::kError;
    s.info = "POSE STALE";
  } else if (!step_error_.empty()) {
    s.level = StatusLevel::kError;
    s.info = "Controller error: " + step_error_;
  } else if (!motion_allowed(now_s)) {
    s.level = StatusLevel::kWarning;
    s.info = !motion_enabled_       ? "Safe speed zero: runstop."
             : !page_motion_allowed_ ? "Safe speed zero: operator page runstop."
                                     : "Safe speed zero: no runstop heard.";
  } else {
    s.level = StatusLevel::kOk;
    s.info = "Controller OK";
    s.safe_stop = false;
  }
  return s;
}

}  // namespace mppi::ros
