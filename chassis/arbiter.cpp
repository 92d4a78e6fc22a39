#include "chassis/arbiter.hpp"

#include <cmath>

#include "base/error.hpp"

namespace mppi::chassis {

bool SafetySettings::is_valid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(command_max_age_s > 0.0) || !std::isfinite(command_max_age_s))
    return fail("command_max_age_s must be > 0");
  if (!(runstop_max_age_s > 0.0) || !std::isfinite(runstop_max_age_s))
    return fail("runstop_max_age_s must be > 0");
  if (!(watchdog_timeout_s > 0.0) || !std::isfinite(watchdog_timeout_s))
    return fail("watchdog_timeout_s must be > 0");
  if (!(stop_throttle >= -1.f && stop_throttle <= 0.f))
    return fail("stop_throttle must be in [-1, 0] (neutral or brake, never throttle)");
  if (max_runstop_sources < 1) return fail("max_runstop_sources must be >= 1");
  return true;
}

Arbiter::Arbiter(Priorities priorities, SafetySettings settings)
    : priorities_(std::move(priorities)), settings_(settings) {
  std::string why;
  if (!settings_.is_valid(&why)) throw Error("chassis safety settings: " + why);
  command_max_age_ = seconds(settings_.command_max_age_s);
  runstop_max_age_ = seconds(settings_.runstop_max_age_s);
  watchdog_timeout_ = seconds(settings_.watchdog_timeout_s);
  slots_.resize(static_cast<std::size_t>(priorities_.size()));
  runstops_.reserve(static_cast<std::size_t>(settings_.max_runstop_sources));
}

SubmitStatus Arbiter::submit_command(std::string_view sender, const Command& command, Time now,
                                     CommandError* error) {
  const int index = priorities_.index_of(sender);
  return submit_command(index, command, now, error);
}

SubmitStatus Arbiter::submit_command(int index, const Command& command, Time now,
                                     CommandError* error) {
  if (error) *error = CommandError::kNone;
  if (index < 0 || index >= priorities_.size()) {
    ++counters_.unknown_sender;
    return SubmitStatus::kUnknownSender;
  }
  const CommandError e = validate(command);
  if (e != CommandError::kNone) {
    ++counters_.invalid[static_cast<std::size_t>(e)];
    if (error) *error = e;
    return SubmitStatus::kInvalidCommand;
  }
  Slot& s = slots_[static_cast<std::size_t>(index)];
  s.has = true;
  s.command = command;
  s.received = now;
  any_command_ = true;
  last_command_ = now;
  ++counters_.commands_accepted;
  return SubmitStatus::kAccepted;
}

SubmitStatus Arbiter::submit_runstop(std::string_view source, bool motion_enabled, Time now) {
  if (source.empty()) {
    ++counters_.bad_source_name;
    return SubmitStatus::kBadSourceName;
  }
  RunstopSlot* slot = nullptr;
  for (auto& r : runstops_)
    if (r.source == source) slot = &r;
  if (!slot) {
    if (static_cast<int>(runstops_.size()) >= settings_.max_runstop_sources) {
      ++counters_.too_many_sources;
      return SubmitStatus::kTooManySources;
    }
    runstops_.push_back({std::string(source), false, Time(0)});
    slot = &runstops_.back();
  }
  slot->motion_enabled = motion_enabled;
  slot->received = now;
  ++counters_.runstops_accepted;
  return SubmitStatus::kAccepted;
}

Decision Arbiter::decide(Time now) const {
  Decision d;
  d.command = Command{0.f, settings_.stop_throttle, 0.f, actuator::kAll};

  int fresh_runstops = 0;
  bool all_allow = true;
  for (const auto& r : runstops_) {
    if (now - r.received < runstop_max_age_) {
      ++fresh_runstops;
      all_allow = all_allow && r.motion_enabled;
    }
  }
  d.motion_enabled = fresh_runstops > 0 && all_allow;

  d.watchdog_tripped = !any_command_ || now - last_command_ >= watchdog_timeout_;
  if (d.watchdog_tripped) return d;  // all neutral, commanders kWatchdog

  d.steering_commander = d.throttle_commander = d.front_brake_commander = kNoCommander;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const Slot& s = slots_[i];
    if (!s.has || now - s.received >= command_max_age_) continue;
    const int who = static_cast<int>(i);
    if (d.steering_commander == kNoCommander && (s.command.actuators & actuator::kSteering)) {
      d.steering_commander = who;
      d.command.steering = s.command.steering;
    }
    if (d.throttle_commander == kNoCommander && (s.command.actuators & actuator::kThrottle)) {
      d.throttle_commander = who;
      d.command.throttle = s.command.throttle;
    }
    if (d.front_brake_commander == kNoCommander && (s.command.actuators & actuator::kFrontBrake)) {
      d.front_brake_commander = who;
      d.command.front_brake = s.command.front_brake;
    }
  }
  if (!d.motion_enabled) {
    d.throttle_commander = kRunstop;
    d.command.throttle = settings_.stop_throttle;
  }
  return d;
}

std::string_view Arbiter::commander_name(int commander) const {
  if (commander == kRunstop) return "runstop";
  if (commander == kWatchdog) return "watchdog";
  if (commander < 0 || commander >= priorities_.size()) return "none";
  return priorities_.entries()[static_cast<std::size_t>(commander)].sender;
}

}  // namespace mppi::chassis
