// Cost-map image loader (costs/cost_map_io.cpp over OpenCV's image decoders) for a 16 x 16 pixel
// map (bounds 0..1.6 m at 10 pixels per meter); the first byte picks the channel and the row order.
// The rest is decoded from memory by CostMap::decode_image, the part of CostMap::load_image after
// it has read the file (every check of the loader is there; no file is written per input).
#include "fuzz/fuzz_input.hpp"
#include "mppi/cost_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  mppi::ImageMapSpec spec;
  spec.x_min_m = 0.f;
  spec.x_max_m = 1.6f;
  spec.y_min_m = 0.f;
  spec.y_max_m = 1.6f;
  spec.pixels_per_meter = 10.f;
  spec.channel = static_cast<mppi::ImageMapSpec::Channel>(data[0] % 4);
  spec.row0_is_y_max = (data[0] & 4) != 0;
  mppi::fuzz::expect_value_or_error([&] { mppi::CostMap::decode_image(data + 1, size - 1, "fuzz input", spec); });
  return 0;
}
