#pragma once
// Deadline statistics of a fixed-rate loop: per tick the latency from the tick's scheduled
// release to the end of its work; an overrun is a tick that ended after its deadline (the
// next release); skipped ticks are releases dropped because the loop was late.
#include <cstddef>
#include <string>
#include <vector>

namespace mppi::chassis {

struct DeadlineStats {
  long ticks = 0;            // ticks run
  long overruns = 0;         // ticks whose work ended after release + period
  long skipped = 0;          // releases dropped after an overrun (the loop never bursts)
  double period_ms = 0.0;
  double p50_ms = 0.0;       // latency percentiles over the kept window
  double p99_ms = 0.0;
  double max_ms = 0.0;       // max latency over the kept window

  std::string to_string() const;
};

// Keeps the last `capacity` latencies (allocated once) and the counters.
class DeadlineRecorder {
 public:
  explicit DeadlineRecorder(double period_ms, std::size_t capacity = 65536);
  void record(double latency_ms, bool overrun) noexcept;
  void add_skipped(long n) noexcept { skipped_ += n; }
  DeadlineStats stats() const;  // sorts a copy: call outside the loop

 private:
  double period_ms_;
  std::vector<double> ring_;
  std::size_t next_ = 0;
  long ticks_ = 0, overruns_ = 0, skipped_ = 0;
};

// Nearest-rank percentile (p in [0, 100]) of unsorted values; 0 for none.
double nearest_rank_percentile(std::vector<double> values, double p);

}  // namespace mppi::chassis
