#include "chassis/deadline_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mppi::chassis {

std::string DeadlineStats::to_string() const {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "%ld ticks at %.1f ms: latency p50 %.3f ms, p99 %.3f ms, max %.3f ms; "
                "%ld overruns, %ld skipped",
                ticks, period_ms, p50_ms, p99_ms, max_ms, overruns, skipped);
  return buf;
}

DeadlineRecorder::DeadlineRecorder(double period_ms, std::size_t capacity)
    : period_ms_(period_ms), ring_(std::max<std::size_t>(1, capacity)) {}

void DeadlineRecorder::record(double latency_ms, bool overrun) noexcept {
  ring_[next_ % ring_.size()] = latency_ms;
  ++next_;
  ++ticks_;
  overruns_ += overrun;
}

double nearest_rank_percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  const auto n = v.size();
  auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(n)));
  rank = std::clamp<std::size_t>(rank, 1, n);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(rank - 1), v.end());
  return v[rank - 1];
}

DeadlineStats DeadlineRecorder::stats() const {
  DeadlineStats s;
  s.ticks = ticks_;
  s.overruns = overruns_;
  s.skipped = skipped_;
  s.period_ms = period_ms_;
  std::vector<double> kept(ring_.begin(),
                           ring_.begin() + static_cast<std::ptrdiff_t>(std::min(next_, ring_.size())));
  s.p50_ms = nearest_rank_percentile(kept, 50);
  s.p99_ms = nearest_rank_percentile(kept, 99);
  s.max_ms = kept.empty() ? 0.0 : *std::max_element(kept.begin(), kept.end());
  return s;
}

}  // namespace mppi::chassis
