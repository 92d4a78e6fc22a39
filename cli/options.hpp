#pragma once
// Option groups that several programs take, declared once: model choice by registry name
// (the help lists the registered names), track, seed, output folder, threads and backend, data
// folder; and model-parameter help text from the registry's parameter tables.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "mppi/backend_choice.hpp"

namespace mppi::cli {

// --model NAME style option: one of `allowed` (empty = every registered model) or of `extra`
// (names outside the registry, e.g. "corrected"). The help lists the valid names.
CLI::Option* add_model_option(CLI::App& app, const std::string& flag, std::string& model, const std::string& what,
                              std::vector<std::string> allowed = {}, const std::vector<std::string>& extra = {});

// --track NAME: a built-in track (sim::Track::names()).
CLI::Option* add_track_option(CLI::App& app, std::string& track, const std::string& what = "track");

// --seed N.
CLI::Option* add_seed_option(CLI::App& app, std::uint64_t& seed, const std::string& what = "noise seed");

// --out DIR (or FILE): where the program writes.
CLI::Option* add_out_option(CLI::App& app, std::string& out, const std::string& what);

// --threads N: CPU threads, 0 = all.
CLI::Option* add_threads_option(CLI::App& app, int& threads);

// --backend NAME: auto | cpu | vulkan (factory/make_controller.hpp).
CLI::Option* add_backend_option(CLI::App& app, BackendChoice& backend);

// --data-dir DIR: the data folder (sets MPPI_DATA_DIR for this process; sim/data_dir.hpp).
CLI::Option* add_data_dir_option(CLI::App& app, std::string& data_dir);

// "<model> parameters (YAML key = default [unit], valid range: meaning):" and one line per
// parameter of the model's table, restricted to `keys` when it is not empty (a key the table
// lacks is listed by name after them). Empty for a model without a parameter table.
std::string model_parameter_help(std::string_view model, const std::vector<std::string>& keys = {});

// A validator for "A:B" pairs of numbers (time windows, speed ranges).
CLI::Validator number_pair(const std::string& shape = "T0:T1");
// Splits a valid number_pair text.
std::pair<double, double> parse_number_pair(const std::string& text);

// Splits "a,b,c" (empty items dropped).
std::vector<std::string> split_list(const std::string& text);

}  // namespace mppi::cli
