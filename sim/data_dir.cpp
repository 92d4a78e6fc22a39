#include "sim/data_dir.hpp"

#include <cstdlib>
#include <filesystem>

#include "mppi/error.hpp"

#ifndef MPPI_DEFAULT_DATA_DIR
#define MPPI_DEFAULT_DATA_DIR "data"
#endif

namespace mppi::sim {

std::string data_dir() {
  const char* env = std::getenv("MPPI_DATA_DIR");
  const bool from_env = env != nullptr && *env != '\0';
  const std::string dir = from_env ? std::string(env) : std::string(MPPI_DEFAULT_DATA_DIR);
  std::error_code ec;
  if (!std::filesystem::is_directory(std::filesystem::path(dir) / "autorally", ec))
    throw Error("data folder '" + dir + "' (from " +
                (from_env ? std::string("$MPPI_DATA_DIR") : std::string("the build default")) +
                ") has no autorally/ subfolder; set MPPI_DATA_DIR to the project's data/ folder");
  return dir;
}

std::string data_file(const std::string& relative) {
  const std::string path = data_dir() + "/" + relative;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error("data file not found: " + path);
  return path;
}

}  // namespace mppi::sim
