#pragma once
// How every program of the project parses its command line (CLI11): the shared settings and
// the exit rules. --help prints the help and exits 0; an unknown flag or a bad value prints
// "<program>: <what is wrong, naming the flag or run-file key>" and a pointer to --help on
// stderr, and exits 2.
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace mppi::cli {

// Exit status of a usage error (unknown flag, bad value, bad run file).
inline constexpr int kUsageExit = 2;

// Shared settings: a flag given twice takes its last value (as the hand-written parsers did),
// defaults are captured for --help and --dump-config, and the help is wide enough to read.
void configure(CLI::App& app);

// Parses the arguments (without the program name), then runs `after_parse` (e.g. reading a run
// file), which may throw CLI::ParseError. Throws CLI::ParseError on a usage error or --help.
void parse_args(CLI::App& app, std::vector<std::string> args,
                const std::function<void()>& after_parse = {});

// Parses argv as parse_args does and handles the outcome. Returns -1 when the program should go
// on; otherwise the exit status after printing the help (0) or the error (kUsageExit).
int parse(CLI::App& app, int argc, char** argv, const std::function<void()>& after_parse = {});

// A usage error found after parsing (a missing input, values that do not fit together).
// Throw it from the after_parse hook; `flag` is named in the message.
CLI::ValidationError usage_error(const std::string& flag, const std::string& what);

}  // namespace mppi::cli
