// The control-loop runner: deadline statistics checked against a hand-run timeline on a fake
// clock; with real threads, a controller that hangs never stalls the chassis (the watchdog
// neutralises the car instead).
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <random>
#include <thread>

#include "chassis/chassis.hpp"
#include "chassis/control_loop.hpp"

using namespace mppi::chassis;

TEST_CASE("deadline statistics match an independently computed timeline", "[chassis][loop]") {
  std::mt19937 rng(11);
  const std::vector<long> work_ms = {1, 3, 5, 12, 19, 20, 21, 39, 40, 41, 75};
  std::vector<long> drawn(500);
  for (auto& d : drawn) d = work_ms[std::uniform_int_distribution<std::size_t>(0, work_ms.size() - 1)(rng)];

  FakeClock clock(Time(std::chrono::milliseconds(1000)));
  CommandMailbox mailbox;
  std::size_t i = 0;
  std::vector<long> published_at_ms;
  ControlLoopSettings settings;
  settings.rate_hz = 50.0;  // 20 ms
  ControlLoop loop(
      settings, clock, [](std::span<float> x) { x[0] = 1.f; return true; },
      [&](std::span<const float>) {
        clock.advance(std::chrono::milliseconds(drawn[i++]));  // the "computation"
        return Command{0.1f, 0.2f, 0.f, actuator::kAll};
      },
      mailbox);
  std::atomic<bool> stop{false};
  loop.run(stop, static_cast<long>(drawn.size()));

  // The timeline by hand: each tick starts at its release, a release is the first multiple of
  // 20 ms at or after the previous tick's end.
  long release = 1000, overruns = 0, skipped = 0;
  std::vector<double> latency;
  for (long d : drawn) {
    const long done = release + d;
    latency.push_back(static_cast<double>(d));
    overruns += d > 20;
    const long next = ((done + 19) / 20) * 20;
    skipped += std::max(0L, (next - release) / 20 - 1);
    release = next;
  }
  std::sort(latency.begin(), latency.end());
  const auto s = loop.stats();
  CHECK(s.ticks == 500);
  CHECK(s.overruns == overruns);
  CHECK(s.skipped == skipped);
  CHECK(s.p50_ms == Approx(latency[249]).margin(1e-9));   // nearest rank: ceil(0.5 * 500)
  CHECK(s.p99_ms == Approx(latency[494]).margin(1e-9));   // ceil(0.99 * 500) = 495
  CHECK(s.max_ms == Approx(75.0));
  CHECK(clock.now() == Time(std::chrono::milliseconds(release)));
  // The last command was published, stamped with the time it was ready.
  StampedCommand c;
  std::uint64_t seen = 0;
  REQUIRE(mailbox.try_take(&c, &seen));
  CHECK(c.command.throttle == 0.2f);
}

TEST_CASE("a hung controller never stalls the chassis: the watchdog takes over", "[chassis][loop]") {
  SteadyClock clock;
  Chassis chassis(Priorities({{"mppi", 1}}), Calibration{});
  CommandMailbox mailbox;
  ChassisLoop chassis_loop(chassis, clock, 100.0);
  chassis_loop.add_command_input("mppi", mailbox);
  chassis_loop.add_input([](Arbiter& a, Time now) { a.submit_runstop("ocs", true, now); });

  std::mutex m;
  std::condition_variable cv;
  bool release_controller = false;
  std::atomic<int> controller_ticks{0};
  ControlLoop control(
      ControlLoopSettings{}, clock, [](std::span<float>) { return true; },
      [&](std::span<const float>) {
        if (++controller_ticks == 5) {  // hangs on its 5th step until the test lets it go
          std::unique_lock<std::mutex> lock(m);
          cv.wait(lock, [&] { return release_controller; });
        }
        return Command{0.5f, 0.3f, 0.f, actuator::kAll};
      },
      mailbox);

  std::atomic<bool> stop_chassis{false}, stop_control{false};
  bool saw_controller = false, saw_watchdog_after = false;
  long ticks_after_hang = 0;
  const Calibration cal;
  chassis_loop.set_sink([&](const ChassisOutput& out) {
    if (!out.decision.watchdog_tripped && out.decision.throttle_commander == 0) {
      saw_controller = true;
      CHECK(out.pulses.throttle_us == cal.throttle.pulse_us(0.3f));
    }
    if (saw_controller && controller_ticks >= 5 && out.decision.watchdog_tripped) {
      saw_watchdog_after = true;
      CHECK(out.pulses.throttle_us == cal.throttle.center_us);
      CHECK(out.pulses.steering_us == cal.steering.center_us);
      if (++ticks_after_hang >= 20) stop_chassis = true;  // the chassis keeps ticking
    }
  });
  std::thread control_thread([&] { control.run(stop_control); });
  std::thread chassis_thread([&] { chassis_loop.run(stop_chassis, 3000); });  // <= 30 s
  chassis_thread.join();
  stop_control = true;
  {
    std::lock_guard<std::mutex> lock(m);
    release_controller = true;
  }
  cv.notify_all();
  control_thread.join();
  CHECK(saw_controller);
  CHECK(saw_watchdog_after);
  CHECK(ticks_after_hang >= 20);
}
