#pragma once
// Time for the chassis: a steady clock in production, a fake one that tests move by hand.
// Times are nanoseconds since the clock's own epoch.
#include <atomic>
#include <chrono>
#include <thread>

namespace mppi::chassis {

using Duration = std::chrono::nanoseconds;
using Time = std::chrono::nanoseconds;  // since the clock's epoch

inline constexpr Duration seconds(double s) {
  return Duration(static_cast<Duration::rep>(s * 1e9 + (s >= 0 ? 0.5 : -0.5)));
}
inline constexpr double to_seconds(Duration d) { return static_cast<double>(d.count()) * 1e-9; }

class Clock {
 public:
  virtual ~Clock() = default;
  virtual Time now() const = 0;
  // Waits until now() >= t (returns at once if it already is).
  virtual void sleep_until(Time t) = 0;
};

// std::chrono::steady_clock: monotonic, never jumps with the wall clock.
class SteadyClock final : public Clock {
 public:
  Time now() const override {
    return std::chrono::duration_cast<Duration>(
        std::chrono::steady_clock::now().time_since_epoch());
  }
  void sleep_until(Time t) override {
    std::this_thread::sleep_until(std::chrono::steady_clock::time_point(
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(t)));
  }
};

// A clock that only moves when told; sleep_until jumps to the wake-up time. Thread-safe.
class FakeClock final : public Clock {
 public:
  explicit FakeClock(Time start = Time(0)) : t_(start.count()) {}
  Time now() const override { return Time(t_.load()); }
  void sleep_until(Time t) override {
    auto cur = t_.load();
    while (cur < t.count() && !t_.compare_exchange_weak(cur, t.count())) {
    }
  }
  void set(Time t) { t_.store(t.count()); }
  void advance(Duration d) { t_.fetch_add(d.count()); }

 private:
  std::atomic<Duration::rep> t_;
};

}  // namespace mppi::chassis
