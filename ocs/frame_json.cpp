#include "ocs/frame_json.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "chassis/arbiter.hpp"

namespace mppi::ocs {
namespace {

double mm(double v) { return std::isfinite(v) ? std::round(v * 1000.0) / 1000.0 : 0.0; }
double sig(double v) { return std::isfinite(v) ? static_cast<double>(static_cast<float>(v)) : 0.0; }

}  // namespace

std::string commander_name(int commander, const std::vector<chassis::PriorityEntry>& priorities) {
  if (commander >= 0 && commander < static_cast<int>(priorities.size())) return priorities[commander].sender;
  if (commander == chassis::kRunstop) return "runstop";
  if (commander == chassis::kWatchdog) return "watchdog";
  if (commander == kCommanderNotReported) return "not reported";
  return "none";
}

std::string frame_json(const LiveFrame& f, const sim::PathPredictor& predictor,
                       const std::vector<chassis::PriorityEntry>& priorities, bool paused, int path_stride) {
  using nlohmann::json;
  const double speed = std::hypot(f.state.vx_mps, f.state.vy_mps);
  const double slip = speed > 0.5 ? std::atan2(f.state.vy_mps, std::fabs(f.state.vx_mps)) : 0.0;
  json j = {
      {"step", f.step},
      {"t", mm(f.t_s)},
      {"x", mm(f.state.x_m)},
      {"y", mm(f.state.y_m)},
      {"yaw", mm(f.state.yaw_rad)},
      {"vx", mm(f.state.vx_mps)},
      {"vy", mm(f.state.vy_mps)},
      {"speed", mm(speed)},
      {"slip", mm(slip)},
      {"steer", mm(f.output.steer)},
      {"throttle", mm(f.output.throttle)},
      {"applied_steer", mm(f.applied.steer)},
      {"applied_throttle", mm(f.applied.throttle)},
      {"optimizer_ms", mm(f.optimizer_ms)},
      {"ess", mm(f.effective_sample_size)},
      {"valid_samples", f.valid_samples},
      {"samples", f.num_samples},
      {"laps", f.laps_completed},
      {"crashes", f.crashes},
      {"progress", mm(f.progress_m)},
      {"target_speed", mm(f.target_speed_mps)},
      {"paused", paused},
  };
  const ChassisStatus& c = f.chassis;
  j["chassis"] = {{"present", c.present},
                  {"motion_enabled", c.motion_enabled},
                  {"watchdog_tripped", c.watchdog_tripped},
                  {"steering", commander_name(c.steering_commander, priorities)},
                  {"throttle", commander_name(c.throttle_commander, priorities)},
                  {"front_brake", commander_name(c.front_brake_commander, priorities)},
                  {"commands_accepted", c.commands_accepted},
                  {"runstops_accepted", c.runstops_accepted}};
  // Paths: lane 0 the plan, then the rollouts with their weights.
  json plan = json::array(), rollouts = json::array(), weights = json::array();
  if (predictor && f.paths > 0 && f.horizon > 0) {
    std::vector<float> xy(static_cast<std::size_t>(f.paths) * (f.horizon + 1) * 2, 0.f);
    predictor(f.model_state, f.controls, f.paths, xy);
    const int stride = std::max(1, path_stride);
    for (int p = 0; p < f.paths; ++p) {
      json path = json::array();
      for (int t = 0; t <= f.horizon; t += stride) {
        const int tt = (t + stride > f.horizon) ? f.horizon : t;  // always end at the horizon
        const float* q = xy.data() + (static_cast<std::size_t>(p) * (f.horizon + 1) + tt) * 2;
        path.push_back(mm(q[0]));
        path.push_back(mm(q[1]));
        if (tt == f.horizon) break;
      }
      if (p == 0) plan = std::move(path);
      else {
        rollouts.push_back(std::move(path));
        weights.push_back(sig(f.weights[p]));
      }
    }
  }
  j["plan"] = std::move(plan);
  j["rollouts"] = std::move(rollouts);
  j["weights"] = std::move(weights);
  return j.dump();
}

}  // namespace mppi::ocs
