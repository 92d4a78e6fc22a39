#include "ros/latency_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "base/error.hpp"
#include "sim/summary.hpp"

namespace mppi::ros {
namespace {

double recent_mean(const std::vector<double>& v, std::size_t n) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(n, v.size());
  double sum = 0.0;
  for (std::size_t i = v.size() - k; i < v.size(); ++i) sum += v[i];
  return sum / static_cast<double>(k);
}

std::string number(double x) {
  if (!std::isfinite(x)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.4f", x);
  return buf;
}

std::string percentiles(const std::vector<double>& v) {
  const double max = v.empty() ? std::numeric_limits<double>::quiet_NaN() : *std::max_element(v.begin(), v.end());
  return "{\"p50\": " + number(sim::percentile(v, 50)) + ", \"p99\": " + number(sim::percentile(v, 99)) +
         ", \"max\": " + number(max) + "}";
}

}  // namespace

double TimingStats::latency_ms_percentile(double p) const { return sim::percentile(latency_ms_, p); }
double TimingStats::optimizer_ms_percentile(double p) const { return sim::percentile(optimizer_ms_, p); }
double TimingStats::recent_pose_interval_s(std::size_t n) const { return recent_mean(pose_interval_s_, n); }
double TimingStats::recent_optimizer_s(std::size_t n) const { return recent_mean(optimizer_ms_, n) * 1e-3; }

std::string TimingStats::to_json() const {
  return "{\"commands\": " + std::to_string(latency_ms_.size()) + ", \"latency_ms\": " + percentiles(latency_ms_) +
         ", \"optimizer_ms\": " + percentiles(optimizer_ms_) + ", \"pose_interval_s\": " +
         percentiles(pose_interval_s_) + ", \"safe_stops\": " + std::to_string(safe_stops_) +
         ", \"errors\": " + std::to_string(errors_) + "}\n";
}

void TimingStats::write_json(const std::string& path) const {
  std::ofstream out(path);
  if (!out) throw Error("timing stats: cannot write " + path);
  out << to_json();
  if (!out) throw Error("timing stats: write failed: " + path);
}

}  // namespace mppi::ros
