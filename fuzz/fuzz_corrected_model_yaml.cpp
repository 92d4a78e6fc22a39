// Corrected-model files: nominal model, its parameters and the effects around it
// (dynamics/corrected_model_io.cpp); what is read is written again and read back.
#include "dynamics/corrected_model.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mppi::fuzz::expect_value_or_error([&] {
    const mppi::CorrectedModelFile m = mppi::corrected_model_from_yaml(mppi::fuzz::as_text(data, size), "fuzz.yaml");
    // A file this program writes must read back.
    mppi::corrected_model_from_yaml(mppi::corrected_model_to_yaml(m), "written.yaml");
  });
  return 0;
}
