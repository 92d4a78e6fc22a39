// mppi-udp-bridge: the vehicle end of the UDP chassis interface, in front of a simulated car.
// A stack in any language sends command and runstop datagrams (docs/CHASSIS.md) to
// 127.0.0.1:47800; the bridge runs the chassis at a fixed rate (priorities, runstop, watchdog,
// calibration to pulse widths), drives the built-in single-track car with the pulse widths in
// real time and answers every client with state datagrams. With --key FILE every datagram is
// authenticated (HMAC-SHA256; off loopback the key is required). On exit it prints the datagram
// counters by rejection reason and the chassis loop's deadline statistics.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

#include "base/error.hpp"
#include "chassis/chassis.hpp"
#include "chassis/udp_adapter.hpp"
#include "cli/app.hpp"
#include "cli/options.hpp"
#include "dynamics/single_track.hpp"
#include "dynamics/vehicle_params.hpp"
#include "sim/data_dir.hpp"
#include "sim/lap_counter.hpp"
#include "sim/plant.hpp"
#include "sim/track.hpp"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

}  // namespace

int main(int argc, char** argv) {
  using namespace mppi;
  using namespace mppi::chassis;
  std::string bind = "127.0.0.1", calibration_file, priorities_file, track_name = "gazebo", key_file;
  int port = udp::kDefaultPort;
  double rate_hz = 100.0, duration_s = 0.0;
  bool quiet = false;
  SafetySettings safety;
  CLI::App app{"The vehicle end of the UDP chassis interface, in front of a simulated car (docs/CHASSIS.md).",
               "mppi-udp-bridge"};
  cli::configure(app);
  app.add_option("--bind", bind, "IPv4 address to listen on (127.0.0.1: loopback only)")->type_name("ADDR");
  app.add_option("--port", port, "UDP port")->type_name("N")->check(CLI::Range(0, 65535).description(""));
  app.add_option("--key", key_file,
                 "authenticate datagrams with this key file (64 hex digits, mode 600; required off loopback)")
      ->type_name("FILE");
  app.add_option("--rate", rate_hz, "chassis rate [Hz]")->type_name("HZ")->check(CLI::PositiveNumber.description(""));
  app.add_option("--calibration", calibration_file, "chassis calibration YAML (default data/config/chassis_calibration.yaml)")
      ->type_name("FILE");
  app.add_option("--priorities", priorities_file, "controller priorities YAML (default data/config/chassis_priorities.yaml)")
      ->type_name("FILE");
  app.add_option("--stop-throttle", safety.stop_throttle, "throttle while stopped, in [-1, 0] (0: neutral)")->type_name("V");
  cli::add_track_option(app, track_name, "track the simulated car starts on");
  app.add_option("--duration", duration_s, "stop after S seconds; 0 = until Ctrl-C")->type_name("S");
  app.add_flag("--quiet", quiet, "no status line per second");
  std::string data_dir;
  cli::add_data_dir_option(app, data_dir);
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  try {
    const Calibration calibration = Calibration::load_yaml(
        calibration_file.empty() ? sim::data_file("config/chassis_calibration.yaml") : calibration_file);
    Priorities priorities = Priorities::load_yaml(
        priorities_file.empty() ? sim::data_file("config/chassis_priorities.yaml") : priorities_file);
    Chassis chassis(priorities, calibration, safety);
    udp::ServerSettings server_settings;
    server_settings.bind_address = bind;
    server_settings.port = port;
    if (!key_file.empty()) server_settings.key = udp::Key::load(key_file);
    udp::UdpChassisServer server(server_settings);

    // The simulated car: AutoRally's single-track model on the track's start line.
    const sim::Track track = sim::Track::load(track_name);
    sim::Plant<SingleTrack> plant(
        SingleTrack(load_single_track_params(sim::data_file("config/autorally_single_track.yaml"))));
    const sim::Pose2 start = track.start_pose();
    VehicleState s0;
    s0.x_m = static_cast<float>(start.x_m);
    s0.y_m = static_cast<float>(start.y_m);
    s0.yaw_rad = static_cast<float>(start.yaw_rad);
    plant.reset(s0);
    sim::LapCounter laps(track);
    laps.reset({start.x_m, start.y_m}, 0.0);

    SteadyClock clock;
    const Time t0 = clock.now();
    ChassisLoop loop(chassis, clock, rate_hz);
    loop.add_input([&](Arbiter& a, Time now) { server.poll(a, now); });
    const float period_s = static_cast<float>(1.0 / rate_hz);
    Time next_status = t0 + seconds(1.0);
    loop.set_sink([&](const ChassisOutput& out) {
      // The link carries whole microseconds; the simulated servos read them back.
      const PulseWidths pulses = out.pulses.rounded();
      const Command applied = calibration.values(pulses);
      plant.advance(Control{applied.steering, applied.throttle}, period_s);
      const double t = to_seconds(out.time - t0);
      const VehicleState s = plant.vehicle_state();
      laps.update({s.x_m, s.y_m}, t);
      udp::StateMessage msg;
      msg.time_s = t;
      msg.state = s.to_array();
      msg.applied = {applied.steering, applied.throttle, applied.front_brake};
      msg.pulses_us = {static_cast<std::uint16_t>(pulses.steering_us),
                       static_cast<std::uint16_t>(pulses.throttle_us),
                       static_cast<std::uint16_t>(pulses.front_brake_us)};
      msg.motion_enabled = out.decision.motion_enabled;
      msg.watchdog_tripped = out.decision.watchdog_tripped;
      server.send_state(msg, out.time);
      if (!quiet && out.time >= next_status) {
        next_status += seconds(1.0);
        const Arbiter& a = chassis.arbiter();
        std::fprintf(stderr,
                     "t %6.1f s | steer %-9s %4.0f us | throttle %-9s %4.0f us | brake %4.0f us | "
                     "%s | v %4.1f m/s | laps %d | rx %ld, rejected %ld (unauthenticated %ld)\n",
                     t, std::string(a.commander_name(out.decision.steering_commander)).c_str(),
                     pulses.steering_us,
                     std::string(a.commander_name(out.decision.throttle_commander)).c_str(),
                     pulses.throttle_us, pulses.front_brake_us,
                     out.decision.motion_enabled ? "motion enabled" : "RUNSTOP", s.vx_mps,
                     laps.laps_completed(), server.counters().received,
                     server.counters().total_rejected(), server.counters().unauthenticated());
      }
    });
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::fprintf(stderr, "mppi-udp-bridge: listening on %s:%d (%s), chassis at %.0f Hz, %d controllers\n",
                 bind.c_str(), server.port(), server_settings.key ? "authenticated" : "no key: loopback only",
                 rate_hz, priorities.size());
    std::thread timer([&] {  // --duration is wall-clock time
      const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s);
      while (duration_s > 0 && !g_stop && std::chrono::steady_clock::now() < end)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (duration_s > 0) g_stop = true;
    });
    loop.run(g_stop);
    g_stop = true;
    timer.join();

    const auto& c = server.counters();
    std::printf("datagrams received %ld: commands accepted %ld, runstops accepted %ld, rejected %ld "
                "(unauthenticated %ld)\n",
                c.received, c.commands_accepted, c.runstops_accepted, c.total_rejected(), c.unauthenticated());
    for (int r = 1; r < udp::kRejectCount; ++r)
      if (c.rejected[static_cast<std::size_t>(r)])
        std::printf("  rejected, %s: %ld\n", udp::to_string(static_cast<udp::Reject>(r)),
                    c.rejected[static_cast<std::size_t>(r)]);
    std::printf("chassis loop: %s\n", loop.stats().to_string().c_str());
    std::printf("laps %d", laps.laps_completed());
    for (double lt : laps.lap_times_s()) std::printf(" %.2f", lt);
    std::printf("\n");
  } catch (const Error& e) {
    std::fprintf(stderr, "mppi-udp-bridge: %s\n", e.what());
    return 1;
  }
  return 0;
}
