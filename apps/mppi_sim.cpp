// mppi-sim: MPPI driving laps of a built-in track in the headless simulator. Its options
// (cli/sim_command_line.cpp) may also come from a YAML run file (--config run.yaml).
#include <cstdio>
#include <iostream>
#include <string>

#include "cli/app.hpp"
#include "cli/sim_command_line.hpp"
#include "dynamics/model_registry.hpp"
#include "mppi/error.hpp"
#include "sim/closed_loop.hpp"
#include "sim/summary.hpp"

int main(int argc, char** argv) {
  CLI::App app{"MPPI driving laps of a built-in track in the headless simulator.", "mppi-sim"};
  mppi::cli::SimCommandLine cl;
  mppi::cli::add_sim_options(app, cl);
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
    if (config.progress)
      std::fprintf(stderr, "mppi-sim: %s track, model %s, plant %s, %.1f m/s, K = %d, T = %d, seed %llu\n",
                   config.track.c_str(), config.model.c_str(), config.plant.c_str(),
                   config.target_speed_mps, config.controller.num_samples, config.controller.horizon,
                   static_cast<unsigned long long>(config.controller.seed));
    const mppi::sim::RunSummary summary = mppi::sim::run_closed_loop(config);
    if (config.progress)
      std::fprintf(stderr, "done: %d/%d laps, %d crashes, mean %.2f m/s, max %.2f m/s, optimizer p50 %.2f ms p99 %.2f ms -> %s\n",
                   summary.laps_completed, config.laps, summary.crashes, summary.mean_speed_mps,
                   summary.max_speed_mps, summary.optimizer_ms_p50, summary.optimizer_ms_p99,
                   config.out_dir.c_str());
    if (cl.print_json) std::cout << mppi::sim::to_json(summary) << std::endl;
    return summary.finished ? 0 : 1;
  } catch (const mppi::Error& e) {
    std::fprintf(stderr, "mppi-sim: error: %s\n", e.what());
    return 2;
  }
}
