#pragma once
// The chassis side: the arbiter's decision turned into servo pulse widths by the calibration,
// and a fixed-rate loop (AutoRally: 100 Hz) that collects commands from its inputs, decides and
// writes the actuators. The loop only ever polls its inputs (never waits on a controller), so
// a stalled controller cannot stall the chassis: the watchdog neutralises the outputs instead.
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "chassis/arbiter.hpp"
#include "chassis/calibration.hpp"
#include "chassis/deadline_stats.hpp"
#include "chassis/mailbox.hpp"

namespace mppi::chassis {

struct ChassisOutput {
  Decision decision;    // who sets what, runstop and watchdog state
  PulseWidths pulses;   // calibrated pulse widths, within each actuator's [min, max]
  Time time{0};
};

class Chassis {
 public:
  Chassis(Priorities priorities, Calibration calibration, SafetySettings safety = {});
  Arbiter& arbiter() { return arbiter_; }
  const Arbiter& arbiter() const { return arbiter_; }
  const Calibration& calibration() const { return calibration_; }
  ChassisOutput update(Time now) const;

 private:
  Arbiter arbiter_;
  Calibration calibration_;
};

class ChassisLoop {
 public:
  ChassisLoop(Chassis& chassis, Clock& clock, double rate_hz = 100.0);
  // A local controller publishing through a mailbox under the name `sender` (must be listed in
  // the priorities; otherwise its commands are counted as unknown).
  void add_command_input(std::string sender, CommandMailbox& mailbox);
  // Any other input, polled once per tick on the chassis thread (e.g. a UDP server's drain);
  // it must not block.
  void add_input(std::function<void(Arbiter&, Time now)> poll);
  // Where each tick's output goes (the actuators); must not block.
  void set_sink(std::function<void(const ChassisOutput&)> sink) { sink_ = std::move(sink); }

  // Ticks until `stop` becomes true or max_ticks (if >= 0) ticks have run.
  void run(const std::atomic<bool>& stop, long max_ticks = -1);
  void tick(Time now);  // one tick at `now` (what run() does per period)
  DeadlineStats stats() const { return recorder_.stats(); }
  const ChassisOutput& last_output() const { return last_; }

 private:
  struct MailboxInput {
    std::string sender;
    int index;
    CommandMailbox* mailbox;
    std::uint64_t seen = 0;
  };
  Chassis& chassis_;
  Clock& clock_;
  Duration period_;
  std::vector<MailboxInput> mailboxes_;
  std::vector<std::function<void(Arbiter&, Time)>> inputs_;
  std::function<void(const ChassisOutput&)> sink_;
  DeadlineRecorder recorder_;
  ChassisOutput last_;
};

}  // namespace mppi::chassis
