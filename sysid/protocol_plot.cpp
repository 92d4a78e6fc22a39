#include "sysid/protocol_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

// OpenCV 4's headers mix enum types, which C++20 deprecates; not our code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop

#include "mppi/error.hpp"

namespace mppi::sysid {

namespace {

// One BGR colour per segment 1..6 (validation last, black).
const cv::Scalar kSegmentColours[6] = {{180, 119, 31}, {14, 127, 255}, {44, 160, 44},
                                       {40, 39, 214},  {189, 103, 148}, {0, 0, 0}};
const cv::Scalar kText(20, 20, 20), kGrid(215, 215, 215);

void text(cv::Mat& img, const std::string& s, int x, int y, double scale = 0.5,
          const cv::Scalar& colour = kText) {
  cv::putText(img, s, {x, y}, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

}  // namespace

void plot_protocol(const ProtocolRun& run, const std::string& png_path) {
  const sim::Recording& tr = run.truth;
  if (tr.rows() < 2) throw Error(png_path + ": protocol run has no truth rows to plot");
  const auto& t = tr.column("t");
  const auto& x = tr.column("x");
  const auto& y = tr.column("y");
  const auto& seg = tr.column("segment");
  const int W = 1500, H = 700, map = 650;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  text(img, "simulated estimation protocol: full-vehicle plant, path by manoeuvre | true vx, vy, yaw rate", 20, 28, 0.6);

  // Left: path, equal axes.
  const auto [xmin, xmax] = std::minmax_element(x.begin(), x.end());
  const auto [ymin, ymax] = std::minmax_element(y.begin(), y.end());
  const double span = std::max({*xmax - *xmin, *ymax - *ymin, 1.0});
  const double scale = (map - 80) / span;
  auto px = [&](std::size_t i) {
    return cv::Point(static_cast<int>(40 + (x[i] - *xmin) * scale),
                     static_cast<int>(H - 40 - (y[i] - *ymin) * scale));
  };
  for (std::size_t i = 1; i < tr.rows(); ++i) {
    const int s = std::clamp(static_cast<int>(seg[i]), 1, 6) - 1;
    cv::line(img, px(i - 1), px(i), kSegmentColours[s], 2, cv::LINE_AA);
  }
  char buf[96];
  cv::line(img, {40, H - 20}, {40 + static_cast<int>(10 * scale), H - 20}, kText, 2);
  text(img, "10 m", 45 + static_cast<int>(10 * scale), H - 15, 0.45);
  const auto& names = protocol_segment_names();
  for (int s = 0; s < 6; ++s) {
    cv::line(img, {40, 55 + 20 * s}, {70, 55 + 20 * s}, kSegmentColours[s], 3);
    text(img, std::to_string(s + 1) + " " + names[static_cast<std::size_t>(s)], 78, 60 + 20 * s, 0.45);
  }

  // Right: three time panels.
  const int left = map + 60, right = W - 20;
  const double t0 = t.front(), t1 = t.back();
  auto tx = [&](double tv) { return static_cast<int>(left + (tv - t0) / (t1 - t0) * (right - left)); };
  struct Panel {
    const char* column;
    const char* label;
    double lo, hi;
  };
  const Panel panels[3] = {{"vx", "vx [m/s]", -1, 12}, {"vy", "vy [m/s]", -5, 5}, {"yaw_rate", "yaw rate [rad/s]", -3, 3}};
  const int top = 50, height = (H - top - 40) / 3;
  for (int p = 0; p < 3; ++p) {
    const int y0 = top + p * height, y1 = y0 + height - 25;
    const auto& v = tr.column(panels[p].column);
    auto vy_px = [&](double val) {
      const double u = std::clamp((val - panels[p].lo) / (panels[p].hi - panels[p].lo), 0.0, 1.0);
      return static_cast<int>(y1 - u * (y1 - y0));
    };
    cv::rectangle(img, {left, y0}, {right, y1}, kGrid, 1);
    cv::line(img, {left, vy_px(0)}, {right, vy_px(0)}, kGrid, 1);
    for (std::size_t i = 1; i < tr.rows(); ++i)
      if (seg[i] != seg[i - 1]) cv::line(img, {tx(t[i]), y0}, {tx(t[i]), y1}, kGrid, 1);
    for (std::size_t i = 1; i < tr.rows(); ++i) {
      const int s = std::clamp(static_cast<int>(seg[i]), 1, 6) - 1;
      cv::line(img, {tx(t[i - 1]), vy_px(v[i - 1])}, {tx(t[i]), vy_px(v[i])}, kSegmentColours[s], 1, cv::LINE_AA);
    }
    text(img, panels[p].label, left + 5, y0 + 15, 0.45);
    std::snprintf(buf, sizeof buf, "%g", panels[p].hi);
    text(img, buf, left - 35, y0 + 10, 0.4);
    std::snprintf(buf, sizeof buf, "%g", panels[p].lo);
    text(img, buf, left - 35, y1, 0.4);
  }
  std::snprintf(buf, sizeof buf, "t = %.0f ... %.0f s", t0, t1);
  text(img, buf, left, H - 15, 0.45);
  if (!cv::imwrite(png_path, img)) throw Error(png_path + ": cannot write PNG");
}

}  // namespace mppi::sysid
