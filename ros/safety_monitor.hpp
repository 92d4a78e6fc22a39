#pragma once
// The controller node's safety and health, on plain inputs (no ROS types): whether the pose
// estimate is fresh, what the operator's runstop says, and the node's status as AutoRally's
// pathIntegralStatus carries it (0 ok, 1 warning, 2 error) with its text. A safe stop (neutral
// steering, zero throttle) is due while no pose has come, the pose is older than the timeout,
// the runstop forbids motion (or, when required, has not been heard for its timeout), or the
// controller failed.
#include <optional>
#include <string>

namespace mppi::ros {

struct SafetySettings {
  double pose_timeout_s = 0.5;      // a pose older than this is stale (AutoRally's TIMEOUT)
  bool require_runstop = false;     // true: motion only while a runstop message allows it
  double runstop_timeout_s = 1.0;   // with require_runstop: a runstop older than this forbids motion

  bool is_valid(std::string* why) const;
};

enum class StatusLevel { kOk = 0, kWarning = 1, kError = 2 };

struct NodeStatus {
  StatusLevel level = StatusLevel::kWarning;
  std::string info;
  bool safe_stop = true;  // the command must be the safe stop
};

class SafetyMonitor {
 public:
  explicit SafetyMonitor(SafetySettings settings = {}) : settings_(settings) {}

  // Times are seconds on one clock (the node's).
  void on_pose(double now_s) { last_pose_s_ = now_s; }
  void on_runstop(bool motion_enabled, double now_s) {
    motion_enabled_ = motion_enabled;
    last_runstop_s_ = now_s;
  }
  // The operator page's runstop (a second operator, beside the runstop messages).
  void on_operator_page(bool motion_allowed) { page_motion_allowed_ = motion_allowed; }
  // The controller's last step: ok, or failed with a reason (cleared by the next good step).
  void on_step(bool ok, const std::string& reason = {}) { step_error_ = ok ? std::string() : reason; }

  bool pose_received() const { return last_pose_s_.has_value(); }
  bool pose_stale(double now_s) const { return !last_pose_s_ || now_s - *last_pose_s_ > settings_.pose_timeout_s; }
  bool motion_allowed(double now_s) const;
  // Whether the controller may step: a fresh pose and motion allowed. A failed step does not
  // count here: its output is the stop, and the next pose gets a new step (which clears it).
  bool may_step(double now_s) const { return !pose_stale(now_s) && motion_allowed(now_s); }
  NodeStatus status(double now_s) const;
  const SafetySettings& settings() const { return settings_; }

 private:
  SafetySettings settings_;
  std::optional<double> last_pose_s_, last_runstop_s_;
  bool motion_enabled_ = true;
  bool page_motion_allowed_ = true;
  std::string step_error_;
};

}  // namespace mppi::ros
