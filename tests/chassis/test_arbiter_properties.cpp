// Property test of the chassis rules: thousands of random interleavings of commands (valid and
// invalid, from listed and unlisted controllers, setting any subset of the actuators), runstop
// messages and time steps on a fake clock, each decision compared with a small reference model
// that replays the whole event history from scratch (no state shared with the Arbiter).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "chassis/arbiter.hpp"
#include "chassis/calibration.hpp"

namespace {
using namespace mppi::chassis;

// ---- the reference model: the arbitration rules of docs/CHASSIS.md, written out plainly ----------------------
struct Event {
  enum Kind { kCommand, kRunstop } kind;
  std::string name;      // sender or runstop source
  Command command;       // kCommand
  bool allow = false;    // kRunstop
  long t_ms = 0;
};

struct Reference {
  std::map<std::string, int> priority;  // name -> number (lower wins)
  int max_sources = 16;
  float stop_throttle = 0.f;
  std::vector<Event> events;

  static bool in(float v, float lo, float hi) { return v >= lo && v <= hi; }  // false for NaN
  static bool command_ok(const Command& c) {
    if (c.actuators == 0 || c.actuators > 7) return false;
    if ((c.actuators & 1) && !in(c.steering, -1.f, 1.f)) return false;
    if ((c.actuators & 2) && !in(c.throttle, -1.f, 1.f)) return false;
    if ((c.actuators & 4) && !in(c.front_brake, 0.f, 1.f)) return false;
    return true;
  }
  bool accepted(std::size_t i) const {
    const Event& e = events[i];
    if (e.kind == Event::kCommand) return priority.count(e.name) && command_ok(e.command);
    if (e.name.empty()) return false;
    std::vector<std::string> sources;  // the first max_sources distinct names are remembered
    for (std::size_t j = 0; j <= i; ++j)
      if (events[j].kind == Event::kRunstop && !events[j].name.empty() &&
          std::find(sources.begin(), sources.end(), events[j].name) == sources.end() &&
          static_cast<int>(sources.size()) < max_sources)
        sources.push_back(events[j].name);
    return std::find(sources.begin(), sources.end(), e.name) != sources.end();
  }

  struct Out {
    float steering, throttle, front_brake;
    std::string steering_by, throttle_by, front_brake_by;
    bool motion, watchdog;
  };

  Out decide(long now_ms) const {
    // Latest accepted message of each sender / source.
    std::map<std::string, const Event*> last_command, last_runstop;
    const Event* newest_command = nullptr;
    for (std::size_t i = 0; i < events.size(); ++i) {
      if (!accepted(i)) continue;
      const Event& e = events[i];
      if (e.kind == Event::kCommand) {
        last_command[e.name] = &e;
        newest_command = &e;
      } else {
        last_runstop[e.name] = &e;
      }
    }
    Out o{0.f, stop_throttle, 0.f, "watchdog", "watchdog", "watchdog", false, true};
    int fresh = 0;
    bool allow = true;
    for (const auto& [name, e] : last_runstop)
      if (now_ms - e->t_ms < 2000) ++fresh, allow = allow && e->allow;
    o.motion = fresh > 0 && allow;
    if (newest_command == nullptr || now_ms - newest_command->t_ms >= 100) return o;
    o.watchdog = false;
    o.steering_by = o.throttle_by = o.front_brake_by = "none";
    std::vector<std::pair<int, std::string>> order;
    for (const auto& [name, p] : priority) order.emplace_back(p, name);
    std::sort(order.begin(), order.end());
    for (int a = 0; a < 3; ++a) {
      for (const auto& [p, name] : order) {
        auto it = last_command.find(name);
        if (it == last_command.end() || now_ms - it->second->t_ms >= 200) continue;
        const Command& c = it->second->command;
        if (!(c.actuators & (1 << a))) continue;
        if (a == 0) o.steering = c.steering, o.steering_by = name;
        if (a == 1) o.throttle = c.throttle, o.throttle_by = name;
        if (a == 2) o.front_brake = c.front_brake, o.front_brake_by = name;
        break;
      }
    }
    if (!o.motion) o.throttle = stop_throttle, o.throttle_by = "runstop";
    return o;
  }
};

float random_value(std::mt19937& rng, float lo, float hi) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  switch (std::uniform_int_distribution<int>(0, 11)(rng)) {
    case 0: return lo;
    case 1: return hi;
    case 2: return std::nextafter(hi, 2.f * std::abs(hi) + 1.f);  // just above the range
    case 3: return std::nextafter(lo, -2.f * std::abs(lo) - 1.f);  // just below
    case 4: return nan;
    case 5: return std::uniform_int_distribution<int>(0, 1)(rng) ? inf : -inf;
    case 6: return -0.f;
    case 7: return std::uniform_real_distribution<float>(-5.f, 5.f)(rng);
    default: return std::uniform_real_distribution<float>(lo, hi)(rng);
  }
}

}  // namespace

TEST_CASE("arbiter, runstop and watchdog agree with the reference model on random histories",
          "[chassis][property]") {
  std::mt19937 rng(20261121);
  const std::vector<std::string> names = {"mppi", "waypoints", "joystick", "OCS"};
  const std::vector<std::string> sources = {"ocs", "runstopBox", "xbee", ""};
  // Time steps in ms: many land exactly on the 100 ms / 200 ms / 2 s boundaries.
  const std::vector<long> steps = {0, 1, 10, 20, 50, 90, 99, 100, 101, 110, 190, 199, 200, 201,
                                   500, 1000, 1999, 2000, 2001};
  long checks = 0, watchdog_seen = 0, split_seen = 0, runstop_seen = 0, rejected_seen = 0;
  constexpr int kSequences = 4000;
  for (int seq = 0; seq < kSequences; ++seq) {
    // A random priority list (1-4 controllers, distinct random numbers).
    std::vector<int> numbers(10);
    for (int i = 0; i < 10; ++i) numbers[i] = i;
    std::shuffle(numbers.begin(), numbers.end(), rng);
    const int n = std::uniform_int_distribution<int>(1, 4)(rng);
    Reference ref;
    std::vector<PriorityEntry> entries;
    for (int i = 0; i < n; ++i) {
      entries.push_back({names[i], numbers[i]});
      ref.priority[names[i]] = numbers[i];
    }
    SafetySettings settings;
    settings.max_runstop_sources = std::uniform_int_distribution<int>(1, 3)(rng);
    settings.stop_throttle = std::uniform_int_distribution<int>(0, 1)(rng) ? 0.f : -0.5f;
    ref.max_sources = settings.max_runstop_sources;
    ref.stop_throttle = settings.stop_throttle;
    Arbiter arbiter(Priorities(entries), settings);
    FakeClock clock(Time(std::chrono::milliseconds(
        std::uniform_int_distribution<long>(0, 5000)(rng))));  // any epoch

    const long start_ms = clock.now().count() / 1000000;
    const int events = std::uniform_int_distribution<int>(1, 60)(rng);
    for (int e = 0; e < events; ++e) {
      clock.advance(std::chrono::milliseconds(
          steps[std::uniform_int_distribution<std::size_t>(0, steps.size() - 1)(rng)]));
      const long now_ms = clock.now().count() / 1000000;
      const int what = std::uniform_int_distribution<int>(0, 9)(rng);
      if (what < 6) {
        Event ev{Event::kCommand, "", {}, false, now_ms};
        // Mostly listed controllers, sometimes an intruder.
        ev.name = std::uniform_int_distribution<int>(0, 9)(rng) == 0
                      ? "intruder"
                      : names[std::uniform_int_distribution<int>(0, n - 1)(rng)];
        ev.command.steering = random_value(rng, -1.f, 1.f);
        ev.command.throttle = random_value(rng, -1.f, 1.f);
        ev.command.front_brake = random_value(rng, 0.f, 1.f);
        const int m = std::uniform_int_distribution<int>(0, 12)(rng);
        ev.command.actuators = static_cast<std::uint8_t>(m < 8 ? m : (m < 12 ? 7 : 8 + m % 8));
        if (std::uniform_int_distribution<int>(0, 2)(rng) == 0) {  // a fully valid command
          ev.command.steering = std::uniform_real_distribution<float>(-1.f, 1.f)(rng);
          ev.command.throttle = std::uniform_real_distribution<float>(-1.f, 1.f)(rng);
          ev.command.front_brake = std::uniform_real_distribution<float>(0.f, 1.f)(rng);
          if (ev.command.actuators == 0 || ev.command.actuators > 7) ev.command.actuators = 7;
        }
        ref.events.push_back(ev);
        const auto status = arbiter.submit_command(ev.name, ev.command, clock.now());
        CHECK((status == SubmitStatus::kAccepted) == ref.accepted(ref.events.size() - 1));
        if (status != SubmitStatus::kAccepted) ++rejected_seen;
      } else if (what < 9) {
        Event ev{Event::kRunstop, sources[std::uniform_int_distribution<int>(0, 3)(rng)], {},
                 std::uniform_int_distribution<int>(0, 3)(rng) != 0, now_ms};
        ref.events.push_back(ev);
        const auto status = arbiter.submit_runstop(ev.name, ev.allow, clock.now());
        CHECK((status == SubmitStatus::kAccepted) == ref.accepted(ref.events.size() - 1));
      }
      // Query (after every event, and at a few later instants without new events).
      for (long later : {0L, 0L, 150L}) {
        const Time q = clock.now() + std::chrono::milliseconds(later);
        const Decision d = arbiter.decide(q);
        const auto o = ref.decide(now_ms + later);
        ++checks;
        // Values are copied, never computed: they must be bit-identical.
        REQUIRE(std::memcmp(&d.command.steering, &o.steering, sizeof(float)) == 0);
        REQUIRE(std::memcmp(&d.command.throttle, &o.throttle, sizeof(float)) == 0);
        REQUIRE(std::memcmp(&d.command.front_brake, &o.front_brake, sizeof(float)) == 0);
        REQUIRE(arbiter.commander_name(d.steering_commander) == o.steering_by);
        REQUIRE(arbiter.commander_name(d.throttle_commander) == o.throttle_by);
        REQUIRE(arbiter.commander_name(d.front_brake_commander) == o.front_brake_by);
        REQUIRE(d.motion_enabled == o.motion);
        REQUIRE(d.watchdog_tripped == o.watchdog);
        // Whatever happened, the output is a valid command and only moves when allowed.
        REQUIRE(validate(d.command) == CommandError::kNone);
        if (!d.motion_enabled) REQUIRE(d.command.throttle <= 0.f);
        watchdog_seen += d.watchdog_tripped;
        runstop_seen += !d.motion_enabled && !d.watchdog_tripped;
        split_seen += !d.watchdog_tripped && d.steering_commander >= 0 &&
                      d.front_brake_commander >= 0 &&
                      d.steering_commander != d.front_brake_commander;
      }
    }
    (void)start_ms;
  }
  // The random histories exercised every rule (otherwise the test proves little).
  CHECK(checks > 100000);
  CHECK(watchdog_seen > 1000);
  CHECK(runstop_seen > 1000);
  CHECK(split_seen > 1000);
  CHECK(rejected_seen > 1000);
}

TEST_CASE("no runstop message means stopped, one stale source does not stop the others",
          "[chassis]") {
  Arbiter a(Priorities({{"mppi", 1}}));
  FakeClock clock;
  const Command go{0.3f, 0.8f, 0.f, actuator::kAll};
  a.submit_command("mppi", go, clock.now());
  auto d = a.decide(clock.now());
  CHECK_FALSE(d.motion_enabled);
  CHECK(d.command.throttle == 0.f);
  CHECK(d.command.steering == 0.3f);  // steering still follows the controller
  CHECK(a.commander_name(d.throttle_commander) == "runstop");
  a.submit_runstop("ocs", true, clock.now());
  a.submit_runstop("box", true, clock.now());
  CHECK(a.decide(clock.now()).command.throttle == 0.8f);
  a.submit_runstop("box", false, clock.now());
  CHECK(a.decide(clock.now()).command.throttle == 0.f);
  // The box goes silent while stopped; 2 s later only the OCS counts again.
  clock.advance(seconds(1.95));
  a.submit_runstop("ocs", true, clock.now());
  a.submit_command("mppi", go, clock.now());
  CHECK(a.decide(clock.now()).command.throttle == 0.f);
  clock.advance(seconds(0.05));
  a.submit_command("mppi", go, clock.now());
  CHECK(a.decide(clock.now()).command.throttle == 0.8f);
  // Watchdog: 100 ms without a command -> neutral everything.
  CHECK_FALSE(a.decide(clock.now() + seconds(0.099)).watchdog_tripped);
  d = a.decide(clock.now() + seconds(0.1));
  CHECK(d.watchdog_tripped);
  CHECK(d.command.steering == 0.f);
  CHECK(d.command.throttle == 0.f);
}
