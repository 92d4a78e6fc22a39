#pragma once
// A track cost map: one float per pixel over an axis-aligned world rectangle, looked up with
// AutoRally's world->pixel mapping (costs.cu loadTrackData):
//   col = floor((x - x_min) * ppm), row = floor((y - y_min) * ppm), value = values[row * W + col]
// with W = (x_max - x_min) * ppm and H = (y_max - y_min) * ppm; row 0 is at y_min. Outside the
// map the nearest edge pixel is used (clamp-to-edge, like AutoRally's GPU texture). Values are
// 0 on the centreline, about 1 at the track edge, more outside. The controller hands it to its
// backends (Backend::set_cost_map); the file loaders below are in costs/cost_map_io.cpp.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "base/error.hpp"

namespace mppi {

// How to turn an image into a cost map (AutoRally track_generator.py recipe):
// value = (pixel[channel] + offset) / normalizer.
struct ImageMapSpec {
  enum class Channel { kRed = 0, kGreen = 1, kBlue = 2, kAlpha = 3 };  // RGBA order
  float x_min_m = 0.f, x_max_m = 0.f;  // world x of the image's first / past-last column
  float y_min_m = 0.f, y_max_m = 0.f;  // world y range covered by the rows
  float pixels_per_meter = 0.f;
  Channel channel = Channel::kRed;  // AutoRally's channel0 is the red channel
  float offset = 0.f;               // added to the raw 8/16-bit pixel value
  float normalizer = 2.55f;         // AutoRally gazebo: channel0 = R / 2.55 (255 -> 100)
  // false: image row 0 (the top of the stored image) is y_min - what track_generator.py does
  // (it never flips; checked against gazebo_costmap.npz, made from gazebo_map.png).
  // true: row 0 is y_max, i.e. the image looks like a map with y pointing up.
  bool row0_is_y_max = false;
};

class CostMap {
 public:
  // Plain-data view for the hot loop: copy it into a local before a lane loop so that the
  // compiler keeps the fields in registers (stores to the cost array cannot alias them).
  struct View {
    const float* values;
    float x_min_m, y_min_m, pixels_per_meter;
    float max_col, max_row;  // width - 1, height - 1 as floats
    int width;

    // Branch-free, noexcept, always in range. The clamp is done on the float pixel coordinate
    // before the int conversion, so huge and infinite coordinates clamp to the edge; a NaN
    // coordinate gives column 0 / row 0 (the x_min / y_min edge): std::max(lo, NaN) returns
    // lo because it computes (lo < NaN) ? NaN : lo.
    static int clamp_index(float pixel, float max_index) noexcept {
      return static_cast<int>(std::min(max_index, std::max(0.f, pixel)));  // >= 0: trunc = floor
    }
    int col_of(float x_m) const noexcept { return clamp_index((x_m - x_min_m) * pixels_per_meter, max_col); }
    int row_of(float y_m) const noexcept { return clamp_index((y_m - y_min_m) * pixels_per_meter, max_row); }
    float lookup(float x_m, float y_m) const noexcept { return values[row_of(y_m) * width + col_of(x_m)]; }
  };

  // Throws mppi::Error if the bounds or ppm are not finite / positive, if the extent is not a
  // whole number of pixels, if values.size() != width * height, or if a value is NaN.
  // Header-only so that mppi::core users can build maps in memory.
  CostMap(float x_min_m, float x_max_m, float y_min_m, float y_max_m, float pixels_per_meter,
          std::vector<float> values)
      : x_min_m_(x_min_m), x_max_m_(x_max_m), y_min_m_(y_min_m), y_max_m_(y_max_m),
        ppm_(pixels_per_meter), values_(std::move(values)) {
    width_ = pixel_count(x_min_m, x_max_m, pixels_per_meter, "x");
    height_ = pixel_count(y_min_m, y_max_m, pixels_per_meter, "y");
    const std::size_t expected = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
    if (expected > static_cast<std::size_t>(std::numeric_limits<int>::max()))
      throw Error("CostMap: " + std::to_string(width_) + " x " + std::to_string(height_) +
                  " pixels is too large (the lookup indexes with int)");
    if (values_.size() != expected)
      throw Error("CostMap: " + std::to_string(values_.size()) + " values, expected " +
                  std::to_string(width_) + " x " + std::to_string(height_) + " = " +
                  std::to_string(expected) + " (from the bounds and pixels_per_meter)");
    for (std::size_t i = 0; i < values_.size(); ++i)
      if (std::isnan(values_[i]))
        throw Error("CostMap: value NaN at row " + std::to_string(i / width_) + ", col " +
                    std::to_string(i % width_));
  }

  // AutoRally npz: xBounds (2), yBounds (2), pixelsPerMeter (1), channel0 (W*H, row-major,
  // row 0 at y_min). Other arrays are ignored. Errors name the file and the array.
  static CostMap load_npz(const std::string& path);
  // Any image OpenCV reads (PNG, ...), 8 or 16 bits, 1/3/4 channels (gray counts as R=G=B,
  // missing alpha as 255). The image must be exactly W x H pixels for the spec's bounds.
  // Reads the file's bytes and hands them to decode_image.
  static CostMap load_image(const std::string& path, const ImageMapSpec& spec);
  // The same from the bytes of an image file in memory (all of load_image's checks happen
  // here); `source` names them in error messages (load_image passes the path). Decoded in
  // memory by OpenCV: the formats that OpenCV 4 decodes only through a temporary file are
  // refused by their signature before decoding: Radiance HDR and OpenEXR (float pixels, which a
  // cost map refuses anyway) and DICOM.
  static CostMap decode_image(const std::uint8_t* bytes, std::size_t size, const std::string& source,
                              const ImageMapSpec& spec);
  // AutoRally's <track>.cfg (a Python dict: xBounds, yBounds, pixelsPerMeter, rOffset,
  // rNormalizer, ..., channelMap, imageRotation, flip) -> the spec for the image channel that
  // becomes channel0. Like track_generator.py it ignores "flip"; imageRotation must be 0.
  // Reads the file and hands its text to parse_autorally_track_cfg.
  static ImageMapSpec read_autorally_track_cfg(const std::string& path);
  // The same from the text of such a file (all of the reader's checks happen here); `source`
  // names it in error messages (read_autorally_track_cfg passes the path).
  static ImageMapSpec parse_autorally_track_cfg(const std::string& text, const std::string& source);

  float x_min_m() const noexcept { return x_min_m_; }
  float x_max_m() const noexcept { return x_max_m_; }
  float y_min_m() const noexcept { return y_min_m_; }
  float y_max_m() const noexcept { return y_max_m_; }
  float pixels_per_meter() const noexcept { return ppm_; }
  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  const std::vector<float>& values() const noexcept { return values_; }
  float at(int row, int col) const noexcept { return values_[static_cast<std::size_t>(row) * width_ + col]; }

  View view() const noexcept {
    return {values_.data(), x_min_m_, y_min_m_, ppm_, static_cast<float>(width_ - 1),
            static_cast<float>(height_ - 1), width_};
  }
  float lookup(float x_m, float y_m) const noexcept { return view().lookup(x_m, y_m); }

  // Pixels along one axis for [lo, hi) at ppm. Throws mppi::Error naming the axis unless the
  // bounds are finite with lo < hi, ppm is finite > 0 and the extent is a whole number of
  // pixels (to 1e-3 px; AutoRally truncates with int(), which silently drops a pixel when
  // float rounding gives 699.9999).
  static int pixel_count(float lo, float hi, float ppm, const char* axis) {
    const std::string name = std::string(axis);
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo))
      throw Error("CostMap: bad " + name + " bounds [" + std::to_string(lo) + ", " +
                  std::to_string(hi) + "] (need finite min < max)");
    if (!std::isfinite(ppm) || !(ppm > 0.f))
      throw Error("CostMap: bad pixels_per_meter " + std::to_string(ppm) + " (need finite > 0)");
    const double n = (static_cast<double>(hi) - lo) * ppm;
    const double whole = std::round(n);
    if (std::abs(n - whole) > 1e-3 || whole < 1.0 || whole > 1e8)
      throw Error("CostMap: " + name + " extent (" + std::to_string(hi) + " - " + std::to_string(lo) +
                  ") * " + std::to_string(ppm) + " = " + std::to_string(n) +
                  " is not a whole number of pixels");
    return static_cast<int>(whole);
  }

 private:
  float x_min_m_, x_max_m_, y_min_m_, y_max_m_, ppm_;
  int width_ = 0, height_ = 0;
  std::vector<float> values_;  // height_ x width_, row-major, row 0 at y_min
};

}  // namespace mppi
