#include "sysid/estimation_plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "mppi/error.hpp"

namespace mppi::sysid {

namespace {

const cv::Scalar kText(40, 40, 40);
const cv::Scalar kAxis(120, 120, 120);
const cv::Scalar kGrid(230, 230, 230);
cv::Scalar palette(int i) {  // BGR
  static const cv::Scalar p[] = {{150, 70, 20}, {20, 120, 240}, {40, 160, 40}, {40, 40, 210}, {150, 150, 150}};
  return p[((i % 5) + 5) % 5];
}

std::string fmt(double v) {
  char b[32];
  if (v != 0 && (std::abs(v) >= 1e4 || std::abs(v) < 1e-3))
    std::snprintf(b, sizeof b, "%.2g", v);
  else
    std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

void draw_panel(cv::Mat& img, const cv::Rect& r, const PlotPanel& p) {
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(img, p.title, {r.x + 8, r.y + 18}, font, 0.5, kText, 1, cv::LINE_AA);
  const cv::Rect a(r.x + 62, r.y + 28, r.width - 78, r.height - 62);
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const auto& s : p.series)
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]);
      y1 = std::max(y1, s.y[i]);
    }
  for (double h : p.hlines)
    if (std::isfinite(h)) {
      y0 = std::min(y0, h);
      y1 = std::max(y1, h);
    }
  if (!(x1 >= x0) || !(y1 >= y0)) return;
  if (x1 - x0 < 1e-12) x1 = x0 + 1;
  if (y1 - y0 < 1e-12 * std::max(1.0, std::abs(y0))) {
    y0 -= 0.5 * std::max(1e-3, std::abs(y0) * 0.01);
    y1 += 0.5 * std::max(1e-3, std::abs(y1) * 0.01);
  }
  const double pad = 0.05 * (y1 - y0);
  y0 -= pad;
  y1 += pad;
  if (p.equal_axes) {
    const double sx = (x1 - x0) / a.width, sy = (y1 - y0) / a.height, s = std::max(sx, sy);
    const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    x0 = cx - 0.5 * s * a.width;
    x1 = cx + 0.5 * s * a.width;
    y0 = cy - 0.5 * s * a.height;
    y1 = cy + 0.5 * s * a.height;
  }
  auto px = [&](double x, double y) {
    return cv::Point(a.x + static_cast<int>(std::lround((x - x0) / (x1 - x0) * a.width)),
                     a.y + a.height - static_cast<int>(std::lround((y - y0) / (y1 - y0) * a.height)));
  };
  for (int i = 0; i <= 4; ++i) {
    const double yv = y0 + (y1 - y0) * i / 4.0, xv = x0 + (x1 - x0) * i / 4.0;
    cv::line(img, px(x0, yv), px(x1, yv), kGrid, 1);
    cv::line(img, px(xv, y0), px(xv, y1), kGrid, 1);
    cv::putText(img, fmt(yv), {r.x + 4, px(x0, yv).y + 4}, font, 0.35, kText, 1, cv::LINE_AA);
    cv::putText(img, fmt(xv), {px(xv, y0).x - 14, a.y + a.height + 14}, font, 0.35, kText, 1, cv::LINE_AA);
  }
  cv::rectangle(img, a, kAxis, 1);
  if (!p.x_label.empty())
    cv::putText(img, p.x_label, {a.x + a.width - 60, a.y + a.height + 28}, font, 0.38, kText, 1, cv::LINE_AA);
  for (double h : p.hlines) {
    if (!std::isfinite(h)) continue;
    for (int xs = a.x; xs < a.x + a.width; xs += 10)
      cv::line(img, {xs, px(x0, h).y}, {std::min(xs + 5, a.x + a.width), px(x0, h).y}, palette(4), 1, cv::LINE_AA);
  }
  cv::Mat clip = img(a);
  int legend_y = a.y + 14;
  for (const auto& s : p.series) {
    std::vector<cv::Point> pts;
    auto flush = [&]() {
      for (std::size_t i = 1; i < pts.size(); ++i) {
        if (s.dashed && (i / 4) % 2) continue;
        cv::line(img, pts[i - 1], pts[i], palette(s.colour), 1, cv::LINE_AA);
      }
      pts.clear();
    };
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        flush();
        continue;
      }
      cv::Point q = px(s.x[i], s.y[i]);
      q.x = std::clamp(q.x, a.x, a.x + a.width);
      q.y = std::clamp(q.y, a.y, a.y + a.height);
      pts.push_back(q);
    }
    flush();
    if (!s.label.empty()) {
      cv::line(img, {a.x + a.width - 120, legend_y - 4}, {a.x + a.width - 100, legend_y - 4}, palette(s.colour), 2);
      cv::putText(img, s.label, {a.x + a.width - 96, legend_y}, font, 0.38, kText, 1, cv::LINE_AA);
      legend_y += 14;
    }
  }
  (void)clip;
}

}  // namespace

void write_panels_png(const std::string& path, const std::string& title, const std::vector<PlotPanel>& panels,
                      int columns, int panel_w, int panel_h) {
  columns = std::max(1, std::min(columns, static_cast<int>(std::max<std::size_t>(1, panels.size()))));
  const int rows = static_cast<int>((panels.size() + columns - 1) / columns);
  const int title_h = 34;
  cv::Mat img(title_h + std::max(1, rows) * panel_h, columns * panel_w, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(img, title, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.6, kText, 1, cv::LINE_AA);
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const int c = static_cast<int>(i) % columns, r = static_cast<int>(i) / columns;
    draw_panel(img, cv::Rect(c * panel_w, title_h + r * panel_h, panel_w, panel_h), panels[i]);
  }
  if (!cv::imwrite(path, img)) throw Error(path + ": cannot write the PNG");
}

}  // namespace mppi::sysid
