// Rosbags as recordings for mppi-fit: the --topic-map / --topic options of the commands that read
// a recording, and the reader registered with sysid::register_recording_reader (".bag"), where
// the build has the rosbag import (sysid/rosbag/, docs/ROSBAG.md).
#pragma once
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

struct FitBagOptions {
  std::string topic_map_file;         // --topic-map FILE.yaml
  std::vector<std::string> topics;    // --topic KEY=VALUE[,KEY=VALUE...], applied after the file
};

// The options every command shares (one set per process: one command runs).
FitBagOptions& fit_bag_options();
// Adds --topic-map and --topic to a command.
void add_bag_options(CLI::App* cmd);
// Registers the ".bag" reader (using fit_bag_options()); without the rosbag import it does nothing
// and load_any_recording refuses a ".bag" saying so.
void register_bag_reader();
