// mppi-soak: a long simulated closed loop through the whole chassis path, run faster than real
// time, that checks what must hold for hours on a car:
//   MPPI (CPU backend) in the control-loop runner -> mailbox -> chassis loop (priorities,
//   runstop, watchdog, calibration) -> simulated servos -> single-track plant on a track,
// while an operator's runstop messages (toggling motion off and on) and malformed datagrams
// (random bytes, truncated messages, wrong types, NaN fields, bad checksums, replays) arrive on
// loopback UDP through the UDP chassis server. The controller stalls now and then, so the
// watchdog has something to catch. Time is simulated (fake clocks); UDP is real.
// Prints one JSON object: resident memory (VmRSS) after warm-up and at the end, and the
// counts of every check; exits 1 if a check fails, 2 for bad options.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <array>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/error.hpp"
#include "chassis/chassis.hpp"
#include "chassis/control_loop.hpp"
#include "chassis/udp_adapter.hpp"
#include "chassis/udp_auth.hpp"
#include "costs/autorally_cost.hpp"
#include "costs/cost_config.hpp"
#include "dynamics/models/single_track_model.hpp"
#include "mppi/controller.hpp"
#include "mppi/cost_map.hpp"
#include "sim/centreline_pose.hpp"
#include "sim/crash_detector.hpp"
#include "sim/data_dir.hpp"
#include "sim/geometry.hpp"
#include "sim/lap_counter.hpp"
#include "sim/plant.hpp"
#include "sim/track.hpp"

namespace {

constexpr const char* kUsage = R"(usage: mppi-soak [options]
  --sim-seconds S        simulated time to run                          (3600)
  --max-wall-seconds S   give up (and fail) after this much wall time   (3600)
  --warmup-seconds S     simulated time before the start RSS is taken   (10)
  --samples K            MPPI samples                                   (256)
  --horizon T            MPPI time steps                                (50)
  --threads N            CPU threads, 0 = all                           (1)
  --seed N               MPPI noise and traffic seed                    (1)
  --speed MPS            target speed                                   (6)
  --malformed-per-second N  malformed datagrams per simulated second    (20)
  --rss-growth-kib N     largest allowed RSS growth after warm-up       (2048)
  --authenticate         sign every datagram with a per-run random key (HMAC-SHA256,
                         docs/CHASSIS.md); the malformed traffic then also sends unsigned
                         and wrongly signed commands
  --out FILE             also write the JSON report to FILE
)";

[[noreturn]] void usage_error(const std::string& msg) {
  std::fprintf(stderr, "mppi-soak: %s\n%s", msg.c_str(), kUsage);
  std::exit(2);
}

double number(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v) || v < 0)
    usage_error(flag + " expects a non-negative number, got '" + text + "'");
  return v;
}

// Resident set size of this process [KiB] (VmRSS in /proc/self/status), -1 if unreadable.
long resident_kib() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
  return -1;
}

// The operator's runstop: motion allowed except for 3 s in every 30 s.
bool operator_allows_motion(double t_s) { return std::fmod(t_s, 30.0) < 27.0; }
// The controller stalls (publishes nothing) for 0.5 s in every 20 s.
bool controller_stalled(double t_s) {
  const double phase = std::fmod(t_s, 20.0);
  return phase >= 13.0 && phase < 13.5;
}

struct Settings {
  double sim_seconds = 3600.0;
  double max_wall_seconds = 3600.0;
  double warmup_seconds = 10.0;
  double speed_mps = 6.0;
  double malformed_per_second = 20.0;
  long rss_growth_limit_kib = 2048;
  bool authenticate = false;
  std::string out;
  mppi::ControllerOptions controller;
};

// Sends malformed datagrams of every kind in turn, each from a sender whose valid messages
// would be accepted, so only the malformation can be the reason for a rejection. With a key,
// every malformed message is signed with it (so it reaches the checks behind the tag), and two
// more kinds test the tag itself: a valid command unsigned, and one signed with another key.
class MalformedTraffic {
 public:
  // `replayed` is the sender whose old sequence numbers are replayed (its messages were accepted).
  MalformedTraffic(int port, std::uint64_t seed, const mppi::chassis::udp::UdpChassisClient& replayed,
                   const std::optional<mppi::chassis::udp::Key>& key)
      : raw_("fuzz", "127.0.0.1", port), rng_(seed), replayed_(replayed), key_(key) {
    std::array<std::uint8_t, mppi::chassis::udp::kKeySize> other{};
    for (auto& b : other) b = static_cast<std::uint8_t>(rng_());
    other_key_ = other;
  }
  void send_one() {
    using namespace mppi::chassis;
    std::uniform_real_distribution<float> value(-1.f, 1.f);
    const Command valid{value(rng_), value(rng_), 0.f, actuator::kAll};
    const auto good = udp::encode_command("backup", ++sequence_, valid);
    std::vector<std::uint8_t> bytes;
    bool sign = key_.has_value();
    switch (kind_++ % (key_ ? 8 : 6)) {
      case 0: {  // random bytes of a random length
        bytes.resize(std::uniform_int_distribution<int>(0, 120)(rng_));
        for (auto& b : bytes) b = static_cast<std::uint8_t>(rng_());
        break;
      }
      case 1:  // a valid command cut short
        bytes.assign(good.begin(), good.begin() + std::uniform_int_distribution<int>(0, good.size() - 1)(rng_));
        break;
      case 2: {  // a type the chassis does not accept (a state message)
        const auto state = udp::encode_state("backup", ++sequence_, udp::StateMessage{});
        bytes.assign(state.begin(), state.end());
        break;
      }
      case 3: {  // a well-formed command with a NaN field
        Command nan_command = valid;
        (rng_() % 2 ? nan_command.steering : nan_command.throttle) = std::nanf("");
        const auto b = udp::encode_command("backup", ++sequence_, nan_command);
        bytes.assign(b.begin(), b.end());
        break;
      }
      case 4:  // one bit flipped: the checksum no longer matches
        bytes.assign(good.begin(), good.end());
        bytes[std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(rng_)] ^=
            static_cast<std::uint8_t>(1u << (rng_() % 8));
        break;
      case 5: {  // a replay: the operator's "motion allowed" under an old sequence number
        const auto b = udp::encode_runstop("OCS", replayed_.next_sequence() - 2, true);
        bytes.assign(b.begin(), b.end());
        break;
      }
      case 6:  // a valid command without its tag
        bytes.assign(good.begin(), good.end());
        sign = false;
        break;
      default: {  // a valid command signed with another key
        const auto tag = udp::hmac_sha256(other_key_, good);
        bytes.assign(good.begin(), good.end());
        bytes.insert(bytes.end(), tag.begin(), tag.end());
        sign = false;
        break;
      }
    }
    if (sign) {
      const udp::Datagram d = udp::seal_datagram(bytes, &*key_);
      raw_.send_raw(d.span());
    } else {
      raw_.send_raw(bytes);
    }
    ++sent_;
  }
  long sent() const { return sent_; }

 private:
  mppi::chassis::udp::UdpChassisClient raw_;
  std::mt19937_64 rng_;
  const mppi::chassis::udp::UdpChassisClient& replayed_;
  std::optional<mppi::chassis::udp::Key> key_;
  std::array<std::uint8_t, mppi::chassis::udp::kKeySize> other_key_{};
  std::uint64_t sequence_ = 1;  // the "backup" controller's sequence numbers
  unsigned kind_ = 0;
  long sent_ = 0;
};

// A random key for one run (std::random_device).
mppi::chassis::udp::Key random_key() {
  std::random_device rd;
  static const char* kHex = "0123456789abcdef";
  std::string hex;
  for (std::size_t i = 0; i < mppi::chassis::udp::kKeySize; ++i) {
    const unsigned b = rd() & 0xffu;
    hex += kHex[b >> 4];
    hex += kHex[b & 15u];
  }
  return mppi::chassis::udp::Key::from_hex(hex, "the soak's random key");
}

int run(const Settings& s) {
  using namespace mppi;
  using namespace mppi::chassis;
  using D = models::SingleTrackModel;
  const auto wall_start = std::chrono::steady_clock::now();
  auto wall_s = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };

  const sim::Track track = sim::Track::load("gazebo");
  AutoRallyCostParams cost_params = load_autorally_cost_params(sim::data_file("config/autorally_cost.yaml"));
  cost_params.target_speed_mps = static_cast<float>(s.speed_mps);
  const AutoRallyCost cost(std::make_shared<const CostMap>(CostMap::load_npz(track.costmap_path())), cost_params);
  const D::Model model = D::load(sim::data_file(D::kDefaultFile));
  Controller controller = make_cpu_controller(model, cost, s.controller);
  sim::Plant<D::Model> plant(model);
  const sim::Pose2 start = track.start_pose();
  auto respawn_at = [&](double x, double y) {
    const sim::Pose2 p = sim::centreline_pose_nearest(track, {x, y});
    VehicleState v;
    v.x_m = static_cast<float>(p.x_m);
    v.y_m = static_cast<float>(p.y_m);
    v.yaw_rad = static_cast<float>(p.yaw_rad);
    plant.reset(v);
  };
  respawn_at(start.x_m, start.y_m);
  sim::LapCounter laps(track);
  laps.reset({start.x_m, start.y_m}, 0.0);
  const sim::CrashDetector crash_detector(track);

  // The chassis: MPPI first, a UDP "backup" controller second (only malformed traffic uses it).
  SafetySettings safety;
  Chassis chassis(Priorities({{"mppi", 0}, {"backup", 1}}), Calibration{}, safety);
  FakeClock chassis_clock, controller_clock;
  ChassisLoop chassis_loop(chassis, chassis_clock, 100.0);
  CommandMailbox mailbox;
  chassis_loop.add_command_input("mppi", mailbox);
  udp::ServerSettings server_settings;
  server_settings.port = 0;  // any free loopback port
  std::optional<udp::Key> key;
  if (s.authenticate) key = random_key();
  server_settings.key = key;
  udp::UdpChassisServer server(server_settings);
  chassis_loop.add_input([&server](Arbiter& arbiter, Time now) { server.poll(arbiter, now); });
  ChassisOutput output;
  chassis_loop.set_sink([&output](const ChassisOutput& o) { output = o; });
  udp::UdpChassisClient operator_station("OCS", "127.0.0.1", server.port(), {}, key);
  MalformedTraffic malformed(server.port(), s.controller.seed, operator_station, key);

  // The control-loop runner, one tick per controller period, on its own fake clock.
  std::vector<float> model_x(D::Model::kNx);
  long controller_nan = 0, controller_failed_steps = 0;
  StepSummary step_summary;
  ControlLoopSettings loop_settings;
  loop_settings.rate_hz = 1.0 / s.controller.dt_s;
  loop_settings.state_size = D::Model::kNx;
  ControlLoop control_loop(
      loop_settings, controller_clock,
      [&](std::span<float> x) {
        D::from_plant(model, plant.state(), D::Model::kNx, x.data());
        return true;
      },
      [&](std::span<const float> x) {
        const auto u = controller.step(x, &step_summary);
        if (step_summary.status != StepStatus::kOk) ++controller_failed_steps;
        if (!std::isfinite(u[control::kSteer]) || !std::isfinite(u[control::kThrottle])) ++controller_nan;
        return Command{u[control::kSteer], u[control::kThrottle], 0.f, actuator::kAll};
      },
      mailbox);
  const std::atomic<bool> never_stop{false};

  const double plant_dt = 0.002, chassis_dt = 0.01;
  const int plant_per_chassis = 5;
  const int chassis_per_control = std::max(1, static_cast<int>(std::lround(s.controller.dt_s / chassis_dt)));
  const double malformed_per_tick = s.malformed_per_second * chassis_dt;
  double malformed_due = 0.0;
  long ticks = 0, runstops_sent = 0, controller_ticks = 0;
  long nan_outputs = 0, out_of_limits = 0, missed_watchdog = 0, false_watchdog = 0, runstop_violations = 0;
  long plant_nan = 0, crashes = 0, stall_ticks = 0, motion_off_ticks = 0;
  double last_publish_s = -1.0;
  bool in_contact = false;
  long rss_start = -1, rss_max = 0;
  bool wall_limit_hit = false;
  double t = 0.0;
  const Calibration& cal = chassis.calibration();
  auto within = [](double v, double lo, double hi) { return v >= lo && v <= hi; };

  while (t < s.sim_seconds - 1e-9) {
    const Time now = seconds(t);
    // The operator station: a runstop message every 0.1 s.
    if (ticks % 10 == 0) {
      operator_station.send_runstop(operator_allows_motion(t));
      ++runstops_sent;
    }
    for (malformed_due += malformed_per_tick; malformed_due >= 1.0; malformed_due -= 1.0) malformed.send_one();
    // The controller, unless stalled.
    if (ticks % chassis_per_control == 0) {
      if (controller_stalled(t)) {
        ++stall_ticks;
      } else {
        controller_clock.set(now);
        control_loop.run(never_stop, 1);
        last_publish_s = t;
        ++controller_ticks;
      }
    }
    chassis_clock.set(now);
    chassis_loop.tick(now);
    const Decision& d = output.decision;
    const Command& c = d.command;
    // Every command within limits: finite, in range, calibrated pulses inside the servo range.
    if (!std::isfinite(c.steering) || !std::isfinite(c.throttle) || !std::isfinite(c.front_brake) ||
        !std::isfinite(output.pulses.steering_us) || !std::isfinite(output.pulses.throttle_us))
      ++nan_outputs;
    else if (!within(c.steering, -1, 1) || !within(c.throttle, -1, 1) || !within(c.front_brake, 0, 1) ||
             !within(output.pulses.steering_us, cal.steering.min_us, cal.steering.max_us) ||
             !within(output.pulses.throttle_us, cal.throttle.min_us, cal.throttle.max_us) ||
             !within(output.pulses.front_brake_us, cal.front_brake.min_us, cal.front_brake.max_us))
      ++out_of_limits;
    // Runstop: once the operator's stop has been sent (one message period), no throttle.
    const bool stop_known = !operator_allows_motion(t) && !operator_allows_motion(t - 0.1);
    if (!d.motion_enabled) ++motion_off_ticks;
    if (stop_known && (d.motion_enabled || c.throttle > safety.stop_throttle)) ++runstop_violations;
    // Watchdog: all neutral once no command came for the timeout (plus one chassis tick);
    // never tripped while commands are fresh.
    const double since_publish = last_publish_s < 0 ? 1e9 : t - last_publish_s;
    if (since_publish > safety.watchdog_timeout_s + chassis_dt + 1e-9 && !d.watchdog_tripped) ++missed_watchdog;
    if (since_publish < safety.watchdog_timeout_s - chassis_dt && last_publish_s >= 0 && d.watchdog_tripped)
      ++false_watchdog;
    // The simulated servos: pulse widths back to actuator positions.
    const Command applied = cal.values(output.pulses);
    const Control command{applied.steering, applied.throttle};
    for (int i = 0; i < plant_per_chassis; ++i) {
      plant.advance(command, static_cast<float>(plant_dt));
      t += plant_dt;
      const VehicleState v = plant.vehicle_state();
      laps.update({v.x_m, v.y_m}, t);
      const sim::CrashResult crash = crash_detector.check(v.x_m, v.y_m, v.yaw_rad);
      if (crash.crashed && !in_contact) {
        ++crashes;
        respawn_at(v.x_m, v.y_m);  // a marshal puts the car back on the centreline, at rest
        controller.reset();
        in_contact = false;
        break;
      }
      in_contact = crash.crashed;
    }
    const VehicleState v = plant.vehicle_state();
    if (!std::isfinite(v.x_m) || !std::isfinite(v.y_m) || !std::isfinite(v.vx_mps)) {
      ++plant_nan;
      respawn_at(start.x_m, start.y_m);
    }
    ++ticks;
    if (rss_start < 0 && t >= s.warmup_seconds) rss_start = resident_kib();
    if (ticks % 1000 == 0) {
      rss_max = std::max(rss_max, resident_kib());
      if (wall_s() > s.max_wall_seconds) {
        wall_limit_hit = true;
        break;
      }
    }
  }
  const long rss_end = resident_kib();
  rss_max = std::max(rss_max, rss_end);
  if (rss_start < 0) rss_start = rss_end;

  const udp::Counters& udp = server.counters();
  const long nan_count = controller_nan + nan_outputs + plant_nan;
  const long udp_wrongly_accepted = udp.commands_accepted;  // only malformed commands were sent
  const bool rss_flat = rss_start > 0 && rss_end - rss_start <= s.rss_growth_limit_kib;
  nlohmann::ordered_json j;
  j["sim_time_s"] = t;
  j["wall_time_s"] = wall_s();
  j["realtime_factor"] = t / std::max(1e-9, wall_s());
  j["finished"] = !wall_limit_hit;
  j["controller"] = {{"samples", s.controller.num_samples}, {"horizon", s.controller.horizon},
                     {"steps", controller_ticks}, {"failed_steps", controller_failed_steps},
                     {"stalled_ticks", stall_ticks}};
  j["rss_kib"] = {{"start", rss_start}, {"end", rss_end}, {"max", rss_max}, {"growth", rss_end - rss_start},
                  {"growth_limit", s.rss_growth_limit_kib}};
  j["nan_count"] = nan_count;
  j["nan"] = {{"controller", controller_nan}, {"chassis_output", nan_outputs}, {"plant", plant_nan}};
  j["missed_watchdog"] = missed_watchdog;
  j["false_watchdog"] = false_watchdog;
  j["out_of_limit_commands"] = out_of_limits;
  j["runstop_violations"] = runstop_violations;
  j["chassis_ticks"] = ticks;
  j["motion_off_ticks"] = motion_off_ticks;
  nlohmann::ordered_json rejected;
  for (int r = 1; r < udp::kRejectCount; ++r)
    if (udp.rejected[r]) rejected[udp::to_string(static_cast<udp::Reject>(r))] = udp.rejected[r];
  j["udp"] = {{"authenticated", s.authenticate},
              {"runstops_sent", runstops_sent},         {"runstops_accepted", udp.runstops_accepted},
              {"malformed_sent", malformed.sent()},      {"received", udp.received},
              {"rejected", udp.total_rejected()},        {"malformed_accepted", udp_wrongly_accepted},
              {"rejected_by_reason", rejected}};
  j["laps"] = laps.laps_completed();
  j["crashes"] = crashes;
  const long udp_lost = runstops_sent + malformed.sent() - udp.received;
  nlohmann::ordered_json failed = nlohmann::ordered_json::array();
  if (wall_limit_hit) failed.push_back("wall time limit reached before the simulated time");
  if (!rss_flat) failed.push_back("resident memory grew by more than the limit");
  if (nan_count) failed.push_back("NaN or inf reached a command or the plant");
  if (missed_watchdog) failed.push_back("the watchdog missed a stalled controller");
  if (false_watchdog) failed.push_back("the watchdog tripped while commands were fresh");
  if (out_of_limits) failed.push_back("a command outside the actuator limits");
  if (runstop_violations) failed.push_back("throttle while the operator's runstop said stop");
  if (udp_wrongly_accepted) failed.push_back("a malformed datagram was accepted");
  if (s.authenticate && (udp.rejected[static_cast<int>(udp::Reject::kUnauthenticated)] == 0 ||
                         udp.rejected[static_cast<int>(udp::Reject::kBadTag)] == 0))
    failed.push_back("unsigned or wrongly signed datagrams were not rejected by their tag");
  if (udp.runstops_accepted != runstops_sent) failed.push_back("a valid runstop message was not accepted");
  if (udp_lost != 0) failed.push_back("datagrams sent on loopback were not all read");
  if (controller_failed_steps) failed.push_back("controller steps failed");
  j["failed_checks"] = failed;
  j["passed"] = failed.empty();
  const std::string text = j.dump(2) + "\n";
  std::fputs(text.c_str(), stdout);
  if (!s.out.empty()) {
    std::ofstream f(s.out);
    f << text;
    if (!f) throw Error(s.out + ": cannot write the report");
  }
  return failed.empty() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Settings s;
  s.controller.num_samples = 256;
  s.controller.horizon = 50;
  s.controller.num_threads = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage_error(flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--help" || flag == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    } else if (flag == "--sim-seconds") s.sim_seconds = number(flag, value());
    else if (flag == "--max-wall-seconds") s.max_wall_seconds = number(flag, value());
    else if (flag == "--warmup-seconds") s.warmup_seconds = number(flag, value());
    else if (flag == "--samples") s.controller.num_samples = static_cast<int>(number(flag, value()));
    else if (flag == "--horizon") s.controller.horizon = static_cast<int>(number(flag, value()));
    else if (flag == "--threads") s.controller.num_threads = static_cast<int>(number(flag, value()));
    else if (flag == "--seed") s.controller.seed = static_cast<std::uint64_t>(number(flag, value()));
    else if (flag == "--speed") s.speed_mps = number(flag, value());
    else if (flag == "--malformed-per-second") s.malformed_per_second = number(flag, value());
    else if (flag == "--rss-growth-kib") s.rss_growth_limit_kib = static_cast<long>(number(flag, value()));
    else if (flag == "--out") s.out = value();
    else if (flag == "--authenticate") s.authenticate = true;
    else usage_error("unknown option " + flag);
  }
  try {
    return run(s);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-soak: %s\n", e.what());
    return 1;
  }
}
