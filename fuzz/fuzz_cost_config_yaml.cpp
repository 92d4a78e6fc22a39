// YAML loader of the AutoRally cost weights (costs/cost_config.cpp).
#include "costs/cost_config.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mppi::fuzz::expect_value_or_error(
      [&] { mppi::parse_autorally_cost_params(mppi::fuzz::as_text(data, size), "fuzz.yaml"); });
  return 0;
}
