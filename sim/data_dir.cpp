#include "sim/data_dir.hpp"

#include <cstdlib>
#include <filesystem>

#include "base/error.hpp"

#ifndef MPPI_DEFAULT_DATA_DIR
#define MPPI_DEFAULT_DATA_DIR "data"
#endif

// Defined in programs built against an installed package (cmake/mppi_installed_data_dir.cpp.in,
// compiled in by mppiConfig.cmake); absent (null) in the build tree.
extern "C" const char* mppi_installed_data_dir() __attribute__((weak));

namespace mppi::sim {

std::string data_dir() {
  const char* env = std::getenv("MPPI_DATA_DIR");
  const bool from_env = env != nullptr && *env != '\0';
  const bool installed = !from_env && mppi_installed_data_dir != nullptr;
  const std::string dir = from_env    ? std::string(env)
                          : installed ? std::string(mppi_installed_data_dir())
                                      : std::string(MPPI_DEFAULT_DATA_DIR);
  std::error_code ec;
  if (!std::filesystem::is_directory(std::filesystem::path(dir) / "autorally", ec))
    throw Error("data folder '" + dir + "' (from " +
                (from_env    ? std::string("$MPPI_DATA_DIR")
                 : installed ? std::string("the installed package")
                             : std::string("the build default")) +
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
