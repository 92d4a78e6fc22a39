#pragma once
// A program's run file: one YAML map whose keys are the program's long flags without the
// dashes (`speed: 8` for --speed 8, `clockwise: true` for the flag --clockwise), as Nav2
// parameter files hold a node's parameters.
//   --config FILE    reads the file; a flag given on the command line wins over its key
//   --dump-config    prints the effective configuration (every key, the file's and the command
//                    line's values, defaults otherwise) as such a file, and exits
// Unknown keys, keys of action flags (--help, --config, ...) and bad values are refused with the
// key and the file named. Relative paths in the file are read from the working directory, as on
// the command line.
#include <string>

#include <CLI/CLI.hpp>

namespace mppi::cli {

class RunFile {
 public:
  // Adds --config and --dump-config to `app`.
  void add_options(CLI::App& app);

  // After parsing the command line: applies the --config file, if one was given, to the
  // options that the command line left unset. Throws CLI::ConfigError naming the file and key.
  void apply(CLI::App& app) const;

  bool dump_requested() const { return dump_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  bool dump_ = false;
};

// Applies the YAML run file `path` to the options of `app` not given on its command line.
void apply_run_file(CLI::App& app, const std::string& path);

// The effective configuration of `app` (after parsing) as a run file: every configurable long
// option, with its description as a comment.
std::string dump_run_file(const CLI::App& app);

}  // namespace mppi::cli
