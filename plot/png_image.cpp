#include "plot/png_image.hpp"

// OpenCV 4's headers mix enum types, which C++20 deprecates; not our code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include "base/error.hpp"

namespace mppi::plot {

RgbImage read_image_rgb(const std::string& path) {
  const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty()) throw Error(path + ": cannot read image");
  RgbImage out;
  out.width = bgr.cols;
  out.height = bgr.rows;
  out.rgb.resize(static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height) * 3);
  std::size_t i = 0;
  for (int r = 0; r < bgr.rows; ++r)
    for (int c = 0; c < bgr.cols; ++c) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(r, c);
      out.rgb[i++] = p[2];
      out.rgb[i++] = p[1];
      out.rgb[i++] = p[0];
    }
  return out;
}

}  // namespace mppi::plot
