// The subcommands of mppi-fit. Each adds itself to the program's command line (CLI11) with its
// options bound to its own settings, and registers what runs it; the run returns the process
// exit status (0 ok, 1 failure, 2 usage error).
#pragma once
#include <functional>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

class FitCommands {
 public:
  // Register `run` for `command`; a sub-command is registered after its parent.
  void add(const CLI::App* command, std::function<int()> run) { runs_.emplace_back(command, std::move(run)); }

  // Runs the deepest command that was parsed. A CLI::ParseError thrown by a run (a usage error
  // found after parsing) is printed, naming the command, and gives exit status 2.
  int run() const;

 private:
  std::vector<std::pair<const CLI::App*, std::function<int()>>> runs_;
};

void add_estimate_command(CLI::App& fit, FitCommands& commands);  // apps/mppi_fit_estimate.cpp
void add_convert_command(CLI::App& fit, FitCommands& commands);   // apps/mppi_fit_convert.cpp
void add_diagnose_command(CLI::App& fit, FitCommands& commands);  // apps/mppi_fit_diagnose.cpp
void add_protocol_command(CLI::App& fit, FitCommands& commands);  // apps/mppi_fit_protocol.cpp
void add_calibrate_command(CLI::App& fit, FitCommands& commands);  // apps/mppi_fit_calibrate.cpp
void add_evaluate_command(CLI::App& fit, FitCommands& commands);   // apps/mppi_fit_evaluate.cpp
