#pragma once
// mppi-sim's command line: its options bound to a closed-loop configuration, with the run file
// (cli/run_file.hpp) so that `--config run.yaml` and the equivalent flags give the same
// configuration.
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/run_file.hpp"
#include "sim/closed_loop.hpp"

namespace mppi::cli {

struct SimCommandLine {
  sim::ClosedLoopConfig config = defaults();
  bool print_json = false;   // --json: summary.json to stdout
  bool quiet = false;        // --quiet: config.progress = false
  bool list_models = false;  // --list-models: print the models and exit
  bool limit_lap = false;    // --limit-lap: print the plant's limit lap on the track, write it, and exit
  std::string data_dir;      // --data-dir
  RunFile run_file;          // --config, --dump-config

  // mppi-sim's defaults: the library's, writing to out/sim, backend auto, upstream's plan smoothing.
  static sim::ClosedLoopConfig defaults();
};

// Adds mppi-sim's options to `app`, bound to `cl` (which must outlive the parse).
void add_sim_options(CLI::App& app, SimCommandLine& cl);

// After parsing: applies the run file and derives what the options do not set directly.
// Throws CLI::ParseError (naming the file and key) for a bad run file.
void finish_sim_options(CLI::App& app, SimCommandLine& cl);

}  // namespace mppi::cli
