#pragma once
// Timing of the controller node: odometry-to-command latency (the command's publication time
// minus the pose's stamp), optimisation time and time between poses, with percentiles, and
// the report the node writes on exit (a small JSON object) for tests and operators.
#include <string>
#include <vector>

namespace mppi::ros {

class TimingStats {
 public:
  void add_latency_ms(double ms) { latency_ms_.push_back(ms); }
  void add_optimizer_ms(double ms) { optimizer_ms_.push_back(ms); }
  void add_pose_interval_s(double s) { pose_interval_s_.push_back(s); }
  void count_safe_stop() { ++safe_stops_; }
  void count_error() { ++errors_; }

  std::size_t commands() const { return latency_ms_.size(); }
  double latency_ms_percentile(double p) const;   // NaN while empty
  double optimizer_ms_percentile(double p) const;
  // Averages over the last n samples (AutoRally's pathIntegralTiming fields), seconds.
  double recent_pose_interval_s(std::size_t n = 50) const;
  double recent_optimizer_s(std::size_t n = 50) const;
  long safe_stops() const { return safe_stops_; }
  long errors() const { return errors_; }
  // {"commands": N, "latency_ms": {"p50":..,"p99":..,"max":..}, "optimizer_ms": {...}, ...}
  std::string to_json() const;
  // Writes to_json() to `path`; throws mppi::Error naming the path when it cannot.
  void write_json(const std::string& path) const;

 private:
  std::vector<double> latency_ms_, optimizer_ms_, pose_interval_s_;
  long safe_stops_ = 0, errors_ = 0;
};

}  // namespace mppi::ros
