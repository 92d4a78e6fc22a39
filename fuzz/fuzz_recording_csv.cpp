// Recording CSV reader (sim/recording.cpp) and the preparation of what it read
// (sysid/prepared_recording.cpp: columns, pieces, sample interval).
#include <sstream>

#include "sysid/prepared_recording.hpp"
#include "fuzz/fuzz_input.hpp"
#include "sim/recording.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mppi::fuzz::expect_value_or_error([&] {
    std::istringstream in(mppi::fuzz::as_text(data, size));
    const mppi::sim::Recording rec = mppi::sim::RecordingReader::read(in, "fuzz.csv");
    // Any minimum row count, down to 0, must be safe.
    mppi::sysid::prepare(rec, "fuzz.csv", /*min_rows=*/size % 4);
  });
  return 0;
}
