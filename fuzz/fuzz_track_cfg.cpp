// AutoRally's <track>.cfg reader (a Python dict; costs/cost_map_io.cpp, its key scanner
// costs/python_dict_text.cpp). The input is parsed as text by CostMap::parse_autorally_track_cfg,
// the part of CostMap::read_autorally_track_cfg after it has read the file (every check of the
// reader is there; no file is written per input).
#include "fuzz/fuzz_input.hpp"
#include "mppi/cost_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = mppi::fuzz::as_text(data, size);
  mppi::fuzz::expect_value_or_error([&] { mppi::CostMap::parse_autorally_track_cfg(text, "fuzz input"); });
  return 0;
}
