#include "plot/colour_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

// OpenCV 4's headers mix enum types, which C++20 deprecates; not our code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop

namespace mppi::plot {

namespace {

// The 256 colours of an OpenCV colour map, as RGB.
std::array<Rgb, 256> table_of(int cv_map) {
  cv::Mat ramp(256, 1, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(i, 0) = static_cast<std::uint8_t>(i);
  cv::Mat bgr;
  cv::applyColorMap(ramp, bgr, cv_map);
  std::array<Rgb, 256> out{};
  for (int i = 0; i < 256; ++i) {
    const cv::Vec3b c = bgr.at<cv::Vec3b>(i, 0);
    out[static_cast<std::size_t>(i)] = {c[2], c[1], c[0]};
  }
  return out;
}

const std::array<Rgb, 256>& table(ColourMapName map) {
  static const std::array<Rgb, 256> turbo = table_of(cv::COLORMAP_TURBO);
  static const std::array<Rgb, 256> viridis = table_of(cv::COLORMAP_VIRIDIS);
  return map == ColourMapName::kViridis ? viridis : turbo;
}

}  // namespace

Rgb palette(int i) {
  static constexpr Rgb kTableau10[10] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},
                                         {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {127, 127, 127},
                                         {188, 189, 34},  {23, 190, 207}};
  return kTableau10[((i % 10) + 10) % 10];
}

Rgb colour_map_rgb(ColourMapName map, double u) {
  const double c = std::isfinite(u) ? std::clamp(u, 0.0, 1.0) : 0.0;
  return table(map)[static_cast<std::size_t>(std::lround(c * 255.0))];
}

Rgb colour_for_value(ColourMapName map, double v, double v_min, double v_max) {
  if (!(v_max > v_min)) return colour_map_rgb(map, 0.0);
  return colour_map_rgb(map, (v - v_min) / (v_max - v_min));
}

std::string to_hex(Rgb c) {
  char b[8];
  std::snprintf(b, sizeof b, "#%02x%02x%02x", c.r, c.g, c.b);
  return b;
}

std::string colour_map_id(ColourMapName map) { return map == ColourMapName::kViridis ? "viridis" : "turbo"; }

}  // namespace mppi::plot
