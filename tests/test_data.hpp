#pragma once
// Paths to the project's data files for tests (data/ of the source tree).
#include <string>

namespace mppi::test {
inline std::string data_path(const std::string& relative) {
  return std::string(MPPI_TEST_DATA_DIR) + "/" + relative;
}
}  // namespace mppi::test
