#pragma once
// The chassis' decision rules (the paper's "AutoRally Chassis Interface" and "Safety System"):
//  - priorities: per actuator, the value of the best-priority controller whose latest valid
//    command is fresher than command_max_age_s (0.2 s) and sets that actuator; so steering and
//    throttle may come from different controllers. No such controller: that actuator neutral.
//  - runstop: motion is enabled only while at least one runstop source has a message fresher
//    than runstop_max_age_s (2 s) and every such fresh message allows motion (AutoRally ANDs
//    the latest message of each source; stale sources are ignored). No message = stopped.
//    Stopped: throttle = stop_throttle (neutral, or a brake), its commander "runstop"; steering
//    and front brake still follow the controllers, so a coasting car can be steered and braked.
//  - watchdog: no valid command from any controller for watchdog_timeout_s (0.1 s), or none
//    yet: every actuator neutral (throttle = stop_throttle).
// Rejected commands (invalid values, unknown sender) change nothing. Not thread-safe: owned by
// the chassis thread; time is passed in (a fake clock in tests). Allocation-free after setup.
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "chassis/clock.hpp"
#include "chassis/command.hpp"
#include "chassis/priorities.hpp"

namespace mppi::chassis {

struct SafetySettings {
  double command_max_age_s = 0.2;    // a controller's command counts while younger than this
  double runstop_max_age_s = 2.0;    // a runstop message counts while younger than this
  double watchdog_timeout_s = 0.1;   // all neutral when no valid command for this long
  float stop_throttle = 0.f;         // throttle when stopped, in [-1, 0]: 0 neutral, < 0 brake
  int max_runstop_sources = 16;      // runstop sources remembered (more are rejected)

  bool is_valid(std::string* why) const;
};

// Who sets an actuator: an index into Priorities::entries(), or one of these.
inline constexpr int kNoCommander = -1;  // nobody fresh: neutral
inline constexpr int kRunstop = -2;      // throttle forced by the runstop
inline constexpr int kWatchdog = -3;     // all actuators forced by the watchdog

struct Decision {
  Command command;                 // values for all three actuators (mask = all), always valid
  int steering_commander = kWatchdog;
  int throttle_commander = kWatchdog;
  int front_brake_commander = kWatchdog;
  bool motion_enabled = false;     // runstop state
  bool watchdog_tripped = true;
};

enum class SubmitStatus : std::uint8_t {
  kAccepted = 0,
  kUnknownSender,        // not in the priority list
  kInvalidCommand,       // see the CommandError
  kBadSourceName,        // empty runstop source name
  kTooManySources,       // more runstop sources than max_runstop_sources
};

struct ArbiterCounters {
  long commands_accepted = 0;
  long runstops_accepted = 0;
  long unknown_sender = 0;
  long too_many_sources = 0;
  long bad_source_name = 0;
  std::array<long, kCommandErrorCount> invalid{};  // by CommandError
};

class Arbiter {
 public:
  Arbiter(Priorities priorities, SafetySettings settings = {});

  // A controller's command received at `now`. `error` (optional) gets the reason of a rejection.
  SubmitStatus submit_command(std::string_view sender, const Command& command, Time now,
                              CommandError* error = nullptr);
  SubmitStatus submit_command(int sender_index, const Command& command, Time now,
                              CommandError* error = nullptr);
  // A runstop message from `source` received at `now`.
  SubmitStatus submit_runstop(std::string_view source, bool motion_enabled, Time now);

  Decision decide(Time now) const;

  // Name of a commander index of a Decision ("runstop", "watchdog", "none" or a controller).
  std::string_view commander_name(int commander) const;
  const Priorities& priorities() const { return priorities_; }
  const SafetySettings& settings() const { return settings_; }
  const ArbiterCounters& counters() const { return counters_; }

 private:
  struct Slot {
    bool has = false;
    Command command;
    Time received{0};
  };
  struct RunstopSlot {
    std::string source;
    bool motion_enabled = false;
    Time received{0};
  };

  Priorities priorities_;
  SafetySettings settings_;
  Duration command_max_age_, runstop_max_age_, watchdog_timeout_;
  std::vector<Slot> slots_;             // one per priority entry, same order
  std::vector<RunstopSlot> runstops_;   // reserved to max_runstop_sources
  bool any_command_ = false;
  Time last_command_{0};
  ArbiterCounters counters_;
};

}  // namespace mppi::chassis
