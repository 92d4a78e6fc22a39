#pragma once
// An 8-bit RGB image read back from a PNG (for tests and tools that check figures).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mppi::plot {

struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, 3 bytes per pixel
  std::array<std::uint8_t, 3> at(int column, int row) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                               static_cast<std::size_t>(column));
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

// Throws mppi::Error if the file cannot be read as an image.
RgbImage read_image_rgb(const std::string& path);

}  // namespace mppi::plot
