#include "chassis/chassis.hpp"

#include <cmath>

#include "base/error.hpp"

namespace mppi::chassis {

Chassis::Chassis(Priorities priorities, Calibration calibration, SafetySettings safety)
    : arbiter_(std::move(priorities), safety), calibration_(calibration) {
  std::string why;
  if (!calibration_.is_valid(&why)) throw Error("chassis calibration: " + why);
}

ChassisOutput Chassis::update(Time now) const {
  ChassisOutput out;
  out.decision = arbiter_.decide(now);
  out.pulses = calibration_.pulses(out.decision.command);
  out.time = now;
  return out;
}

ChassisLoop::ChassisLoop(Chassis& chassis, Clock& clock, double rate_hz)
    : chassis_(chassis), clock_(clock), period_(seconds(1.0 / rate_hz)),
      recorder_(1000.0 / rate_hz) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) throw Error("chassis loop: rate_hz must be > 0");
}

void ChassisLoop::add_command_input(std::string sender, CommandMailbox& mailbox) {
  const int index = chassis_.arbiter().priorities().index_of(sender);
  mailboxes_.push_back({std::move(sender), index, &mailbox, 0});
}

void ChassisLoop::add_input(std::function<void(Arbiter&, Time)> poll) {
  inputs_.push_back(std::move(poll));
}

void ChassisLoop::tick(Time now) {
  for (auto& in : mailboxes_) {
    StampedCommand c;
    if (in.mailbox->try_take(&c, &in.seen))
      chassis_.arbiter().submit_command(in.index, c.command, c.published);
  }
  for (auto& poll : inputs_) poll(chassis_.arbiter(), now);
  last_ = chassis_.update(now);
  if (sink_) sink_(last_);
}

void ChassisLoop::run(const std::atomic<bool>& stop, long max_ticks) {
  Time release = clock_.now();
  for (long n = 0; !stop.load(std::memory_order_relaxed) && (max_ticks < 0 || n < max_ticks); ++n) {
    tick(clock_.now());
    const Time done = clock_.now();
    recorder_.record(to_seconds(done - release) * 1e3, done > release + period_);
    release += period_;
    if (done > release) {  // late: drop the missed releases rather than bursting
      const long missed = static_cast<long>((done - release + period_ - Duration(1)) / period_);
      recorder_.add_skipped(missed);
      release += missed * period_;
    }
    clock_.sleep_until(release);
  }
}

}  // namespace mppi::chassis
