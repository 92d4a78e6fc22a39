#pragma once
// The control-loop runner: runs a controller (MPPI, or any policy) at a fixed rate on the latest
// state and publishes each command to the chassis through a mailbox, which the chassis polls
// without waiting, so a slow controller never blocks the chassis. Reports deadline statistics:
// latency from each tick's scheduled release to its publication (p50, p99, max), overruns
// (published after the next release) and skipped releases (the loop catches up by skipping,
// never by bursting).
#include <atomic>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "chassis/clock.hpp"
#include "chassis/command.hpp"
#include "chassis/deadline_stats.hpp"
#include "chassis/mailbox.hpp"

namespace mppi::chassis {

struct ControlLoopSettings {
  double rate_hz = 50.0;              // controller rate (AutoRally's MPPI: 50 Hz)
  int state_size = 7;                 // floats the state source fills
  std::size_t stats_window = 65536;   // latencies kept for the percentiles

  bool is_valid(std::string* why) const;
};

class ControlLoop {
 public:
  // Fills the latest state; returns false when there is none (nothing is published that tick,
  // so the chassis watchdog neutralises the car if it lasts).
  using StateSource = std::function<bool(std::span<float> state)>;
  // The controller: state -> command.
  using Policy = std::function<Command(std::span<const float> state)>;

  // Where each command goes, with the time it was ready; must not block for long (a mailbox
  // put, a UDP send).
  using Publisher = std::function<void(const Command& command, Time ready)>;

  ControlLoop(ControlLoopSettings settings, Clock& clock, StateSource state, Policy policy,
              Publisher publish);
  // Publishes into a mailbox that a ChassisLoop polls.
  ControlLoop(ControlLoopSettings settings, Clock& clock, StateSource state, Policy policy,
              CommandMailbox& out);

  // Ticks until `stop` becomes true or max_ticks (if >= 0) ticks have run.
  void run(const std::atomic<bool>& stop, long max_ticks = -1);
  DeadlineStats stats() const { return recorder_.stats(); }
  long ticks_without_state() const { return no_state_; }

 private:
  ControlLoopSettings settings_;
  Clock& clock_;
  StateSource state_source_;
  Policy policy_;
  Publisher publish_;
  Duration period_;
  std::vector<float> state_;
  DeadlineRecorder recorder_;
  long no_state_ = 0;
};

}  // namespace mppi::chassis
