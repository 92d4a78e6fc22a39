#include "chassis/control_loop.hpp"

#include <cmath>

#include "base/error.hpp"

namespace mppi::chassis {

bool ControlLoopSettings::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz) || rate_hz > 10000.0)
    return fail("rate_hz must be in (0, 10000]");
  if (state_size < 1) return fail("state_size must be >= 1");
  if (stats_window < 1) return fail("stats_window must be >= 1");
  return true;
}

ControlLoop::ControlLoop(ControlLoopSettings settings, Clock& clock, StateSource state,
                         Policy policy, Publisher publish)
    : settings_(settings), clock_(clock), state_source_(std::move(state)),
      policy_(std::move(policy)), publish_(std::move(publish)), period_(seconds(1.0 / settings.rate_hz)),
      state_(static_cast<std::size_t>(std::max(1, settings.state_size))),
      recorder_(1000.0 / settings.rate_hz, settings.stats_window) {
  std::string why;
  if (!settings_.is_valid(&why)) throw Error("control loop: " + why);
  if (!state_source_ || !policy_ || !publish_)
    throw Error("control loop: state source, policy and publisher are required");
}

ControlLoop::ControlLoop(ControlLoopSettings settings, Clock& clock, StateSource state,
                         Policy policy, CommandMailbox& out)
    : ControlLoop(settings, clock, std::move(state), std::move(policy),
                  [&out](const Command& c, Time ready) { out.put({c, ready}); }) {}

void ControlLoop::run(const std::atomic<bool>& stop, long max_ticks) {
  Time release = clock_.now();
  for (long n = 0; !stop.load(std::memory_order_relaxed) && (max_ticks < 0 || n < max_ticks); ++n) {
    if (state_source_(state_)) {
      const Command c = policy_(state_);
      publish_(c, clock_.now());
    } else {
      ++no_state_;
    }
    const Time done = clock_.now();
    recorder_.record(to_seconds(done - release) * 1e3, done > release + period_);
    release += period_;
    if (done > release) {  // overran: skip the releases already missed
      const long missed = static_cast<long>((done - release + period_ - Duration(1)) / period_);
      recorder_.add_skipped(missed);
      release += missed * period_;
    }
    clock_.sleep_until(release);
  }
}

}  // namespace mppi::chassis
