// mppi-udp-drive: the stack end of the UDP chassis interface, in C++. It runs MPPI (AutoRally's
// network, or the kinematic bicycle) in the control-loop runner at a fixed rate on the state
// datagrams of a chassis (mppi-udp-bridge, or any program speaking docs/CHASSIS.md), sends the
// commands as controller `--name` and, as the operator station `--runstop-name`, a runstop
// message allowing motion. With --key FILE every datagram it sends is signed and only signed
// ones are read (chassis state and parameter messages alike). On exit it prints the runner's
// deadline statistics.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "base/error.hpp"
#include "chassis/control_loop.hpp"
#include "chassis/udp_adapter.hpp"
#include "cli/app.hpp"
#include "cli/options.hpp"
#include "costs/autorally_cost.hpp"
#include "costs/cost_config.hpp"
#include "dynamics/autorally_nn.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "dynamics/model_registry.hpp"
#include "mppi/controller.hpp"
#include "mppi/cost_map.hpp"
#include "sim/data_dir.hpp"
#include "sim/lap_counter.hpp"
#include "sim/track.hpp"
#ifdef MPPI_HAVE_OCS
#include "apps/page_options.hpp"
#include "ocs/loop_page.hpp"
#include "sim/path_predictor.hpp"
#endif

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

}  // namespace

int main(int argc, char** argv) {
  using namespace mppi;
  using namespace mppi::chassis;
  std::string host = "127.0.0.1", name = "mppi", runstop_name = "OCS", model = models::AutoRallyNetworkModel::kName,
              track_name = "gazebo", key_file;
  int port = udp::kDefaultPort, param_port = udp::kDefaultParameterPort, serve_port = -1;
  double speed = 6.0, duration_s = 30.0;
  ControlLoopSettings loop_settings;
  ControllerOptions options;
  CLI::App app{"The stack end of the UDP chassis interface: MPPI at a fixed rate on a chassis' state datagrams "
               "(docs/CHASSIS.md).",
               "mppi-udp-drive"};
  cli::configure(app);
  app.add_option("--host", host, "chassis address")->type_name("ADDR");
  app.add_option("--port", port, "chassis UDP port")->type_name("N")->check(CLI::Range(0, 65535).description(""));
  app.add_option("--key", key_file,
                 "authenticate datagrams with this key file (64 hex digits, mode 600; required off loopback)")
      ->type_name("FILE");
  app.add_option("--name", name, "controller name in the priorities")->type_name("NAME");
  app.add_option("--runstop-name", runstop_name, "runstop source name")->type_name("NAME");
  cli::add_model_option(app, "--model", model, "controller model (its default data file)");
  cli::add_track_option(app, track_name, "track of the cost map");
  app.add_option("--speed", speed, "target speed [m/s]")->type_name("MPS");
  app.add_option("--rate", loop_settings.rate_hz, "controller rate [Hz]")
      ->type_name("HZ")
      ->check(CLI::PositiveNumber.description(""));
  app.add_option("--samples", options.num_samples, "MPPI samples")->type_name("K");
  app.add_option("--horizon", options.horizon, "MPPI time steps")->type_name("T");
  cli::add_threads_option(app, options.num_threads);
  cli::add_seed_option(app, options.seed);
  app.add_option("--duration", duration_s, "stop after S seconds; 0 = until Ctrl-C")->type_name("S");
  app.add_option("--param-port", param_port, "UDP port for parameter messages, 0 = off")
      ->type_name("N")
      ->check(CLI::Range(0, 65535).description(""));
  std::string data_dir;
  cli::add_data_dir_option(app, data_dir);
  app.add_option("--serve", serve_port,
                 "operator page on http://127.0.0.1:PORT/; open the URL it prints (with the page's token) "
                 "(docs/OCS.md)")
      ->type_name("PORT")
      ->check(CLI::Range(0, 65535).description(""));
#ifdef MPPI_HAVE_OCS
  ocs::ServerSettings page_settings;
  apps::add_page_options(app, page_settings.bind_address, page_settings.access);
#endif
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  try {
    const sim::Track track = sim::Track::load(track_name);
    AutoRallyCostParams cost_params = load_autorally_cost_params(sim::data_file("config/autorally_cost.yaml"));
    cost_params.target_speed_mps = static_cast<float>(speed);
    const AutoRallyCost cost(std::make_shared<const CostMap>(CostMap::load_npz(track.costmap_path())),
                             cost_params);
    // Any registered model with its default data; it reads the chassis' common states.
    std::unique_ptr<Controller> controller;
    std::function<void(const float* common, float* model_x)> observe;
#ifdef MPPI_HAVE_OCS
    std::unique_ptr<ocs::LoopPage> page;  // --serve
    StepSummary summary;
#else
    if (serve_port >= 0) throw Error("this build has no operator page (ocs/CMakeLists.txt says why)");
#endif
    with_model(model, [&]<class D>() {
      const std::string default_file = D::kDefaultFile;
      const typename D::Model m = D::load(default_file.empty() ? default_file : sim::data_file(default_file));
      controller = std::make_unique<Controller>(make_cpu_controller(m, cost, options));
      loop_settings.state_size = D::Model::kNx;
      observe = [m](const float* common, float* model_x) { D::from_plant(m, common, state::kCommonStates, model_x); };
#ifdef MPPI_HAVE_OCS
      if (serve_port >= 0) {
        page_settings.port = serve_port;
        page = std::make_unique<ocs::LoopPage>(page_settings, track_name, sim::make_path_predictor(m, options.dt_s),
                                               speed);
      }
#endif
    });

    std::optional<udp::Key> key;
    if (!key_file.empty()) key = udp::Key::load(key_file);
    udp::UdpChassisClient commands(name, host, port, {}, key);
    udp::UdpChassisClient runstop(runstop_name, host, port, {}, key);
    runstop.send_runstop(true);  // announce ourselves, so the chassis starts sending state
    commands.send_command(Command{});  // a neutral command: the chassis answers clients it heard

    // A receiver thread keeps the latest state in a mailbox; the loop never waits for it.
    Mailbox<udp::StateMessage> latest;
    std::atomic<bool> stop_rx{false};
    std::thread receiver([&] {
      while (!stop_rx) {
        if (auto s = commands.receive_state(0.05)) latest.put(*s);
      }
    });
    // Parameter messages: a receiver thread queues them; the loop applies them between steps
    // (it only tries the lock, so it never waits for the receiver).
    std::mutex updates_mutex;
    std::vector<udp::ParameterUpdate> updates, applying;
    updates.reserve(64);
    applying.reserve(64);
    std::unique_ptr<udp::UdpParameterListener> params;
    if (param_port > 0) params = std::make_unique<udp::UdpParameterListener>("127.0.0.1", param_port, 64, key);
    std::thread param_receiver([&] {
      while (params && !stop_rx) {
        if (auto u = params->receive(0.05)) {
          const std::lock_guard<std::mutex> lock(updates_mutex);
          if (updates.size() < 64) updates.push_back(std::move(*u));
        }
      }
    });
    std::uint64_t seen = 0;
    SteadyClock clock;
    udp::StateMessage state_msg;
    bool have_state = false;
    Time state_at{0};
    sim::LapCounter laps(track);
    bool laps_started = false;
    ControlLoop loop(
        loop_settings, clock,
        [&](std::span<float> x) {
#ifdef MPPI_HAVE_OCS
          runstop.send_runstop(!page || page->motion_allowed());  // the operator's heartbeat, every tick
#else
          runstop.send_runstop(true);  // the operator's heartbeat, every tick
#endif
          if (latest.try_take(&state_msg, &seen)) have_state = true, state_at = clock.now();
          // No state, or none for 0.1 s (the chassis is gone): publish nothing this tick.
          if (!have_state || clock.now() - state_at > seconds(0.1)) return false;
          const float* common = state_msg.state.data();
          if (!laps_started) laps.reset({common[0], common[1]}, state_msg.time_s), laps_started = true;
          laps.update({common[0], common[1]}, state_msg.time_s);
          observe(common, x.data());
          return true;
        },
        [&](std::span<const float> x) {
          if (std::unique_lock<std::mutex> lock(updates_mutex, std::try_to_lock); lock && !updates.empty()) {
            applying.swap(updates);
            lock.unlock();
            for (const udp::ParameterUpdate& p : applying) {
              std::string why;
              if (controller->set_cost_param(p.name, p.value, &why))
                std::fprintf(stderr, "mppi-udp-drive: %s = %g (from %s)\n", p.name.c_str(), p.value, p.sender.c_str());
              else
                std::fprintf(stderr, "mppi-udp-drive: parameter from %s refused: %s\n", p.sender.c_str(), why.c_str());
            }
            applying.clear();
          }
#ifdef MPPI_HAVE_OCS
          if (page) {
            page->apply_requests(*controller);
            const auto u = controller->step(x, &summary);
            page->after_step(state_msg.time_s, VehicleState::from_array(state_msg.state.data()), x,
                             {u[control::kSteer], u[control::kThrottle]}, {state_msg.applied[0], state_msg.applied[1]},
                             summary, *controller, state_msg.motion_enabled, state_msg.watchdog_tripped);
            return Command{u[control::kSteer], u[control::kThrottle], 0.f, actuator::kAll};
          }
#endif
          const auto u = controller->step(x);
          return Command{u[control::kSteer], u[control::kThrottle], 0.f, actuator::kAll};
        },
        [&](const Command& c, Time) {
          commands.send_command(c);
        });
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::fprintf(stderr, "mppi-udp-drive: %s MPPI (K = %d, T = %d) at %.0f Hz -> %s:%d as '%s'\n",
                 model.c_str(), options.num_samples, options.horizon, loop_settings.rate_hz,
                 host.c_str(), port, name.c_str());
    std::thread timer([&] {  // --duration is wall-clock time
      const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s);
      while (duration_s > 0 && !g_stop && std::chrono::steady_clock::now() < end)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (duration_s > 0) g_stop = true;
    });
    loop.run(g_stop);
    g_stop = true;
    timer.join();
    runstop.send_runstop(false);  // leave the car stopped
    stop_rx = true;
    receiver.join();
    param_receiver.join();
    std::printf("control loop: %s\n", loop.stats().to_string().c_str());
    std::printf("ticks without state: %ld\n", loop.ticks_without_state());
    std::printf("laps %d", laps.laps_completed());
    for (double lt : laps.lap_times_s()) std::printf(" %.2f", lt);
    std::printf("\n");
  } catch (const Error& e) {
    std::fprintf(stderr, "mppi-udp-drive: %s\n", e.what());
    return 1;
  }
  return 0;
}
