#include "sim/track_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

// OpenCV 4's headers mix enum types, which C++20 deprecates; not our code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop

#include "mppi/error.hpp"

namespace mppi::sim {

namespace {

constexpr int kMarginPx = 30;
constexpr int kPanelPx = 140;  // colour bar and its labels, right of the map
constexpr int kTitleLinePx = 28;
constexpr int kTitlePadPx = 12;

// OpenCV colours are BGR.
const cv::Scalar kBarrierColour(70, 70, 70);
const cv::Scalar kBoundaryColour(0, 0, 0);
const cv::Scalar kCentreColour(185, 185, 185);
const cv::Scalar kStartColour(0, 140, 0);
const cv::Scalar kCrashColour(0, 0, 255);
const cv::Scalar kTextColour(20, 20, 20);

// 256 turbo colours (BGR), from OpenCV's colour map.
const cv::Mat& turbo_lut() {
  static const cv::Mat lut = [] {
    cv::Mat ramp(256, 1, CV_8UC1);
    for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(i, 0) = static_cast<std::uint8_t>(i);
    cv::Mat colours;
    cv::applyColorMap(ramp, colours, cv::COLORMAP_TURBO);
    return colours;
  }();
  return lut;
}

int colour_index(double v, double v_min, double v_max) {
  if (!(v_max > v_min)) return 0;
  const double u = std::clamp((v - v_min) / (v_max - v_min), 0.0, 1.0);
  return static_cast<int>(std::lround(u * 255.0));
}

cv::Scalar speed_bgr(double v, double v_min, double v_max) {
  const cv::Vec3b c = turbo_lut().at<cv::Vec3b>(colour_index(v, v_min, v_max), 0);
  return cv::Scalar(c[0], c[1], c[2]);
}

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> lines;
  std::stringstream ss(s);
  std::string line;
  while (std::getline(ss, line)) lines.push_back(line);
  if (lines.empty()) lines.push_back("");
  return lines;
}

std::string speed_label(double v, const std::string& unit) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.1f %s", v, unit.c_str());
  return buf;
}

}  // namespace

PlotFrame::PlotFrame(const Track& track, int width_px, int title_lines) : width_px_(width_px) {
  if (width_px < 2 * kMarginPx + kPanelPx + 100)
    throw Error("plot width " + std::to_string(width_px) + " px is too small (min " +
                std::to_string(2 * kMarginPx + kPanelPx + 100) + ")");
  const Bounds b = track.bounds();
  const double w_m = std::max(b.x_max - b.x_min, 1e-3);
  const double h_m = std::max(b.y_max - b.y_min, 1e-3);
  map_right_px_ = width_px - kPanelPx - kMarginPx;
  const int map_w = map_right_px_ - kMarginPx;
  px_per_m_ = map_w / w_m;
  left_px_ = kMarginPx;
  top_px_ = kTitlePadPx + kTitleLinePx * std::max(1, title_lines) + kMarginPx;
  height_px_ = top_px_ + static_cast<int>(std::ceil(h_m * px_per_m_)) + kMarginPx;
  x_min_m_ = b.x_min;
  y_max_m_ = b.y_max;
}

std::pair<int, int> PlotFrame::to_pixel(double x_m, double y_m) const {
  return {left_px_ + static_cast<int>(std::lround((x_m - x_min_m_) * px_per_m_)),
          top_px_ + static_cast<int>(std::lround((y_max_m_ - y_m) * px_per_m_))};
}

std::array<std::uint8_t, 3> speed_colour_rgb(double v, double v_min, double v_max) {
  const cv::Vec3b c = turbo_lut().at<cv::Vec3b>(colour_index(v, v_min, v_max), 0);
  return {c[2], c[1], c[0]};
}

void plot_track_run(const std::string& png_path, const Track& track,
                    const std::vector<PathSample>& path,
                    const std::vector<std::pair<float, float>>& crash_points,
                    const std::string& title, const PlotOptions& options) {
  const std::vector<std::string> title_lines = split_lines(title);
  const PlotFrame frame(track, options.width_px, static_cast<int>(title_lines.size()));
  cv::Mat img(frame.height_px(), frame.width_px(), CV_8UC3, cv::Scalar(255, 255, 255));
  const auto px = [&](double x, double y) {
    const auto [c, r] = frame.to_pixel(x, y);
    return cv::Point(c, r);
  };
  const auto draw_closed = [&](const Polyline& line, const cv::Scalar& colour, int thickness) {
    std::vector<cv::Point> pts;
    pts.reserve(line.size());
    for (const Vec2& p : line) pts.push_back(px(p.x, p.y));
    cv::polylines(img, pts, true, colour, thickness, cv::LINE_AA);
  };

  // Track: barriers drawn as pipes of their real width, else the boundary lines.
  if (track.has_barriers()) {
    for (const Barrier& bar : track.barriers())
      draw_closed(bar.centre, kBarrierColour,
                  std::max(2, static_cast<int>(std::lround(2.0 * bar.radius_m * frame.px_per_m()))));
  } else {
    draw_closed(track.inner(), kBoundaryColour, 2);
    draw_closed(track.outer(), kBoundaryColour, 2);
  }
  // Centreline dashed: 1 m drawn, 1 m left out.
  {
    const Polyline& c = track.centreline();
    const auto& arc = track.centreline_arc_m();
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (static_cast<long>(std::floor(arc[i])) % 2 != 0) continue;
      const Vec2 a = c[i], b = c[(i + 1) % c.size()];
      cv::line(img, px(a.x, a.y), px(b.x, b.y), kCentreColour, 1, cv::LINE_AA);
    }
  }
  // Start: a line across the track and an arrow along the driving direction.
  {
    const Pose2 s = track.start_pose();
    const double cy = std::cos(s.yaw_rad), sy = std::sin(s.yaw_rad);
    cv::line(img, px(s.x_m - 1.2 * sy, s.y_m + 1.2 * cy), px(s.x_m + 1.2 * sy, s.y_m - 1.2 * cy),
             kStartColour, 2, cv::LINE_AA);
    cv::arrowedLine(img, px(s.x_m, s.y_m), px(s.x_m + 2.0 * cy, s.y_m + 2.0 * sy), kStartColour, 2,
                    cv::LINE_AA, 0, 0.3);
  }

  // Path coloured by speed. Without anti-aliasing so each segment's pixels are exactly its colour.
  double v_min = options.speed_min_mps, v_max = options.speed_max_mps;
  if (!(v_max > v_min)) {
    v_min = path.empty() ? 0.0 : path[0].speed_mps;
    v_max = v_min;
    for (const PathSample& p : path) {
      v_min = std::min<double>(v_min, p.speed_mps);
      v_max = std::max<double>(v_max, p.speed_mps);
    }
    if (!(v_max > v_min)) v_max = v_min + 1.0;
  }
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const PathSample& a = path[i];
    const PathSample& b = path[i + 1];
    cv::line(img, px(a.x_m, a.y_m), px(b.x_m, b.y_m),
             speed_bgr(0.5 * (a.speed_mps + b.speed_mps), v_min, v_max), 3, cv::LINE_8);
  }
  if (path.size() == 1)
    cv::circle(img, px(path[0].x_m, path[0].y_m), 2, speed_bgr(path[0].speed_mps, v_min, v_max),
               cv::FILLED);

  // Crashes: red crosses.
  for (const auto& [x, y] : crash_points) {
    const cv::Point c = px(x, y);
    constexpr int r = 8;
    cv::line(img, c + cv::Point(-r, -r), c + cv::Point(r, r), kCrashColour, 3, cv::LINE_8);
    cv::line(img, c + cv::Point(-r, r), c + cv::Point(r, -r), kCrashColour, 3, cv::LINE_8);
  }

  // Colour bar: max speed at the top.
  {
    const int x0 = frame.map_right_px() + 30, bar_w = 24;
    const int y0 = kTitlePadPx + kTitleLinePx * static_cast<int>(title_lines.size()) + kMarginPx + 20;
    const int y1 = std::max(y0 + 60, std::min(frame.height_px() - kMarginPx - 20, y0 + 400));
    for (int y = y0; y <= y1; ++y) {
      const double u = 1.0 - static_cast<double>(y - y0) / static_cast<double>(y1 - y0);
      cv::line(img, {x0, y}, {x0 + bar_w, y}, speed_bgr(u, 0.0, 1.0), 1, cv::LINE_8);
    }
    cv::rectangle(img, {x0, y0}, {x0 + bar_w, y1}, kTextColour, 1);
    const int font = cv::FONT_HERSHEY_SIMPLEX;
    cv::putText(img, options.quantity, {x0 - 8, y0 - 10}, font, 0.5, kTextColour, 1, cv::LINE_AA);
    cv::putText(img, speed_label(v_max, options.unit), {x0 + bar_w + 6, y0 + 5}, font, 0.45, kTextColour, 1, cv::LINE_AA);
    cv::putText(img, speed_label(v_min, options.unit), {x0 + bar_w + 6, y1 + 5}, font, 0.45, kTextColour, 1, cv::LINE_AA);
  }
  // Title.
  for (std::size_t i = 0; i < title_lines.size(); ++i)
    cv::putText(img, title_lines[i], {kMarginPx, kTitlePadPx + kTitleLinePx * static_cast<int>(i + 1) - 6},
                cv::FONT_HERSHEY_SIMPLEX, 0.65, kTextColour, 1, cv::LINE_AA);

  bool ok = false;
  try {
    ok = cv::imwrite(png_path, img);
  } catch (const cv::Exception& e) {
    throw Error(png_path + ": cannot write plot (" + e.what() + ")");
  }
  if (!ok) throw Error(png_path + ": cannot write plot");
}

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

}  // namespace mppi::sim
