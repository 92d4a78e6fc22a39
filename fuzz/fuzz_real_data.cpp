// Converters of the real recordings (sysid/real_converters.cpp): DART JetRacer (14 and 10 columns)
// and ETH RC car CSV files, recognised by their header row.
#include "fuzz/fuzz_input.hpp"
#include "sysid/real_data.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mppi::fuzz::expect_value_or_error(
      [&] { mppi::sysid::convert_real_recording(mppi::fuzz::as_text(data, size), "fuzz.csv"); });
  return 0;
}
