// YAML loaders of the chassis adapter: actuator calibration (chassis/calibration.cpp) and
// controller priorities (chassis/priorities.cpp), over chassis/yaml_util.cpp. The first byte
// picks the loader.
#include "chassis/calibration.hpp"
#include "chassis/priorities.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text = mppi::fuzz::as_text(data + 1, size - 1);
  mppi::fuzz::expect_value_or_error([&] {
    if (data[0] % 2 == 0) mppi::chassis::Calibration::parse_yaml(text, "fuzz.yaml");
    else mppi::chassis::Priorities::parse_yaml(text, "fuzz.yaml");
  });
  return 0;
}
