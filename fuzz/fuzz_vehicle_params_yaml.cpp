// YAML loaders of the vehicle models' parameters (dynamics/vehicle_params_io.cpp over
// base/param_yaml.cpp and base/yaml_number.cpp). The first byte picks the model.
#include "dynamics/vehicle_params.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text = mppi::fuzz::as_text(data + 1, size - 1);
  mppi::fuzz::expect_value_or_error([&] {
    switch (data[0] % 4) {
      case 0: mppi::single_track_params_from_yaml(text, "fuzz.yaml"); break;
      case 1: mppi::kinematic_bicycle_params_from_yaml(text, "fuzz.yaml"); break;
      case 2: mppi::double_track_params_from_yaml(text, "fuzz.yaml"); break;
      default: mppi::full_vehicle_params_from_yaml(text, "fuzz.yaml"); break;
    }
  });
  return 0;
}
