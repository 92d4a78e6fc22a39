// mppi-fit: parameter estimation and sim-vs-real tools; dispatches to a subcommand.
#include <cstdio>
#include <string>

#include "cli/app.hpp"
#include "cli/options.hpp"
#include "mppi_fit_bag.hpp"
#include "mppi_fit_commands.hpp"

int FitCommands::run() const {
  for (auto it = runs_.rbegin(); it != runs_.rend(); ++it) {
    if (!it->first->parsed()) continue;
    try {
      return it->second();
    } catch (const CLI::ParseError& e) {
      std::string name;
      for (const CLI::App* a = it->first; a != nullptr; a = a->get_parent()) name = a->get_name() + (name.empty() ? "" : " ") + name;
      std::fprintf(stderr, "%s: %s\nRun with --help for more information.\n", name.c_str(), e.what());
      return mppi::cli::kUsageExit;
    }
  }
  std::fprintf(stderr, "mppi-fit: a command is required\nRun with --help for more information.\n");
  return mppi::cli::kUsageExit;
}

bool mppi_fit_wants_independent_generator(int argc, char** argv);  // apps/mppi_fit_evidence.cpp
int mppi_fit_evidence(int argc, char** argv);

int main(int argc, char** argv) {
  // `diagnose synth|sweep --generator independent`: the independent evidence generator has its own
  // options (docs/EVIDENCE.md) and is kept apart from the diagnosis' code.
  if (argc >= 3 && std::string(argv[1]) == "diagnose" &&
      (std::string(argv[2]) == "synth" || std::string(argv[2]) == "sweep") &&
      mppi_fit_wants_independent_generator(argc - 1, argv + 1))
    return mppi_fit_evidence(argc - 1, argv + 1);
  CLI::App app{"Parameter estimation and sim-vs-real tools (mppi-fit <command> --help for its options).", "mppi-fit"};
  mppi::cli::configure(app);
  // (the command is required by FitCommands::run, so that an unknown flag is named first)
  std::string data_dir;
  mppi::cli::add_data_dir_option(app, data_dir);  // before the command: mppi-fit --data-dir DIR estimate ...
  register_bag_reader();  // a recording may be a rosbag (docs/ROSBAG.md)
  FitCommands commands;
  add_estimate_command(app, commands);
  add_convert_command(app, commands);
  add_diagnose_command(app, commands);
  add_protocol_command(app, commands);
  add_calibrate_command(app, commands);
  add_evaluate_command(app, commands);
  if (const int rc = mppi::cli::parse(app, argc, argv); rc >= 0) return rc;
  return commands.run();
}
