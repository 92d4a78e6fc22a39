// mppi-sim: MPPI driving laps of a built-in track in the headless simulator. Its options
// (cli/sim_command_line.cpp) may also come from a YAML run file (--config run.yaml).
#include <cstdio>
#include <iostream>
#include <string>

#include "base/error.hpp"
#include "cli/app.hpp"
#include "cli/sim_command_line.hpp"
#include "dynamics/model_registry.hpp"
#include "sim/closed_loop.hpp"
#include "sim/limit_lap_report.hpp"
#include "sim/summary.hpp"
#ifdef MPPI_HAVE_LAPTIME
#include "laptime/register_collocation.hpp"
#endif
#ifdef MPPI_HAVE_OCS
#include "apps/page_options.hpp"
#include "ocs/serve.hpp"
#endif

int main(int argc, char** argv) {
#ifdef MPPI_HAVE_LAPTIME
  mppi::laptime::register_collocation_limit_lap();
#endif
  CLI::App app{"MPPI driving laps of a built-in track in the headless simulator.", "mppi-sim"};
  mppi::cli::SimCommandLine cl;
  mppi::cli::add_sim_options(app, cl);
  int serve_port = -1;
  bool serve_fast = false;
  std::string replay_csv;
  app.add_option("--serve", serve_port,
                 "operator page on http://127.0.0.1:PORT/ while driving, in real time; open the URL it prints "
                 "(with the page's token) (docs/OCS.md)")
      ->type_name("PORT")
      ->check(CLI::Range(0, 65535));
#ifdef MPPI_HAVE_OCS
  mppi::ocs::ServeOptions serve;
  mppi::apps::add_page_options(app, serve.bind_address, serve.access);
#endif
  app.add_flag("--fast", serve_fast, "with --serve: do not hold the simulation to wall-clock time");
  app.add_option("--replay", replay_csv, "serve FILE (a recording) on the operator page for replay (with --serve PORT)")
      ->type_name("FILE");
  if (const int rc = mppi::cli::parse(app, argc, argv, [&] { mppi::cli::finish_sim_options(app, cl); }); rc >= 0)
    return rc;
  if (cl.list_models) {
    std::fputs(mppi::models_help().c_str(), stdout);
    return 0;
  }
  if (cl.run_file.dump_requested()) {
    std::fputs(mppi::cli::dump_run_file(app).c_str(), stdout);
    return 0;
  }
  const mppi::sim::ClosedLoopConfig& config = cl.config;
  try {
    if (cl.limit_lap) {
      const mppi::sim::LimitLaps laps = mppi::sim::report_limit_lap(config);
      std::printf("limit lap (%s) of the %s plant on %s%s:\n%s", config.limit_lap_method.c_str(), config.plant.c_str(), config.track.c_str(),
                  config.clockwise ? " (clockwise)" : "", mppi::sim::describe_limit_laps(laps).c_str());
      if (!config.out_dir.empty())
        std::printf("-> %s/limit_lap.csv, %s/limit_lap.png, %s/standing_limit_lap.csv\n", config.out_dir.c_str(),
                    config.out_dir.c_str(), config.out_dir.c_str());
      return 0;
    }
#ifdef MPPI_HAVE_OCS
    serve.port = serve_port;
    serve.realtime = !serve_fast;
    if (!replay_csv.empty()) {
      if (serve_port < 0) {
        std::fprintf(stderr, "mppi-sim: --replay needs --serve PORT\n");
        return 2;
      }
      return mppi::ocs::serve_recording(replay_csv, "", serve);
    }
#else
    if (serve_port >= 0 || !replay_csv.empty()) {
      std::fprintf(stderr, "mppi-sim: this build has no operator page (ocs/CMakeLists.txt says why)\n");
      return 2;
    }
#endif
    if (config.progress)
      std::fprintf(stderr, "mppi-sim: %s track, model %s, plant %s, %.1f m/s, K = %d, T = %d, seed %llu\n",
                   config.track.c_str(), config.model.c_str(), config.plant.c_str(),
                   config.target_speed_mps, config.controller.num_samples, config.controller.horizon,
                   static_cast<unsigned long long>(config.controller.seed));
#ifdef MPPI_HAVE_OCS
    const mppi::sim::RunSummary summary =
        serve_port >= 0 ? mppi::ocs::run_closed_loop_with_page(config, serve) : mppi::sim::run_closed_loop(config);
#else
    const mppi::sim::RunSummary summary = mppi::sim::run_closed_loop(config);
#endif
    if (config.progress)
      std::fprintf(stderr, "done: %d/%d laps, %d crashes, %d stalls, mean %.2f m/s, max %.2f m/s, optimizer p50 %.2f ms p99 %.2f ms -> %s\n",
                   summary.laps_completed, config.laps, summary.crashes, summary.stalls, summary.mean_speed_mps,
                   summary.max_speed_mps, summary.optimizer_ms_p50, summary.optimizer_ms_p99,
                   config.out_dir.c_str());
    if (cl.print_json) std::cout << mppi::sim::to_json(summary) << std::endl;
    return summary.finished ? 0 : 1;
  } catch (const mppi::Error& e) {
    std::fprintf(stderr, "mppi-sim: error: %s\n", e.what());
    return 2;
  }
}
