#pragma once
// Where the simulator finds its data files (cost maps, track boundaries, model weights):
// $MPPI_DATA_DIR if set; else, in a program built against an installed package
// (find_package(mppi)), that installation's share/mppi/data wherever it was installed or
// copied to; else the data/ folder of the source tree (the build tree's programs).
#include <string>

namespace mppi::sim {

// The data root. Throws mppi::Error if the folder has no autorally/ subfolder (naming the
// folder and where its path came from).
std::string data_dir();

// data_dir() + "/" + relative. Throws mppi::Error naming the full path if the file is missing.
std::string data_file(const std::string& relative);

// The shipped AutoRally network (data/autorally/models), relative to the data folder.
inline constexpr const char* kDefaultNetworkFile = "autorally/models/autorally_nnet_09_12_2018.npz";

// `npz_path`, or the shipped network where it is empty.
inline std::string network_file_or_default(const std::string& npz_path) {
  return npz_path.empty() ? data_file(kDefaultNetworkFile) : npz_path;
}

}  // namespace mppi::sim
