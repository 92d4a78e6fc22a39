// AutoRally's <track>.cfg reader (a Python dict; costs/cost_map_io.cpp).
#include "costs/cost_map.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = mppi::fuzz::write_temp_file(data, size, ".cfg");
  mppi::fuzz::expect_value_or_error([&] { mppi::CostMap::read_autorally_track_cfg(path); });
  return 0;
}
