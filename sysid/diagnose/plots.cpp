#include "sysid/diagnose/plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "mppi/error.hpp"

namespace mppi::diagnose {
namespace {

const cv::Scalar kBefore(40, 40, 220), kAfter(200, 90, 20), kMeasured(20, 20, 20), kGrid(210, 210, 210);

// A plot panel: a pixel rectangle and the data ranges mapped onto it.
struct Panel {
  cv::Rect r;
  double x0, x1, y0, y1;
  cv::Point px(double x, double y) const {
    const double fx = (x - x0) / std::max(1e-12, x1 - x0), fy = (y - y0) / std::max(1e-12, y1 - y0);
    return {r.x + static_cast<int>(std::lround(fx * r.width)), r.y + r.height - static_cast<int>(std::lround(fy * r.height))};
  }
};

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.4) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

void frame(cv::Mat& img, const Panel& p, const std::string& title, const std::string& xlabel) {
  cv::rectangle(img, p.r, cv::Scalar(90, 90, 90), 1);
  if (p.y0 < 0 && p.y1 > 0) cv::line(img, p.px(p.x0, 0), p.px(p.x1, 0), kGrid, 1);
  text(img, title, {p.r.x, p.r.y - 6}, 0.42);
  text(img, fmt(p.x0), {p.r.x, p.r.y + p.r.height + 14}, 0.35);
  text(img, fmt(p.x1), {p.r.x + p.r.width - 30, p.r.y + p.r.height + 14}, 0.35);
  text(img, xlabel, {p.r.x + p.r.width / 2 - 30, p.r.y + p.r.height + 14}, 0.35);
  text(img, fmt(p.y1), {p.r.x - 46, p.r.y + 10}, 0.35);
  text(img, fmt(p.y0), {p.r.x - 46, p.r.y + p.r.height}, 0.35);
}

void polyline(cv::Mat& img, const Panel& p, const std::vector<double>& xs, const std::vector<double>& ys,
              const cv::Scalar& colour, int thickness = 1) {
  std::vector<cv::Point> pts;
  auto flush = [&] {
    if (pts.size() > 1) cv::polylines(img, pts, false, colour, thickness, cv::LINE_AA);
    pts.clear();
  };
  for (std::size_t i = 0; i < xs.size(); ++i) {
    if (!std::isfinite(xs[i]) || !std::isfinite(ys[i])) {
      flush();
      continue;
    }
    pts.push_back(p.px(xs[i], std::clamp(ys[i], p.y0, p.y1)));
  }
  flush();
}

void write_png(const std::string& path, const cv::Mat& img) {
  if (!cv::imwrite(path, img)) throw Error("cannot write plot " + path);
}

}  // namespace

void plot_residual_vs_regime(const std::string& png, const DiagData& d, const ResidualSeries& before,
                             const ResidualSeries& after, const std::vector<char>& mask) {
  const int regimes[] = {0, 3, 4, 1};
  const int W = 1200, H = 760, left = 70, top = 50, pw = 250, ph = 170, gx = 40, gy = 75;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  text(img, "mean residual (measured - predicted) / " + fmt(before.horizon_s) +
                " s per regime bin, held out: nominal (red) vs corrected (blue)", {left, 22}, 0.5);
  for (int c = 0; c < kChannels; ++c) {
    for (int g = 0; g < 4; ++g) {
      const auto reg = regime_variable(d, regimes[g]);
      const auto b0 = bin_residual(before.e[c], reg, mask, 8, 1.0);
      const auto b1 = bin_residual(after.e[c], reg, mask, 8, 1.0);
      if (b0.empty() || b1.empty()) continue;
      double lo = b0.front().lo, hi = b0.back().hi, ymax = 1e-6;
      for (const auto* bs : {&b0, &b1})
        for (const auto& b : *bs) ymax = std::max(ymax, std::abs(b.mean));
      Panel p{cv::Rect(left + g * (pw + gx), top + c * (ph + gy), pw, ph), lo, hi, -1.1 * ymax, 1.1 * ymax};
      if (!(hi > lo)) p.x1 = lo + 1;
      frame(img, p, std::string(kChannelNames[c]) + " [" + kChannelUnits[c] + "/s] vs " + kRegimeNames[regimes[g]],
            kRegimeUnits[regimes[g]]);
      for (const auto* bs : {&b0, &b1}) {
        std::vector<double> xs, ys;
        for (const auto& b : *bs) {
          xs.push_back(0.5 * (b.lo + b.hi));
          ys.push_back(b.mean);
        }
        const cv::Scalar col = bs == &b0 ? kBefore : kAfter;
        polyline(img, p, xs, ys, col, 2);
        for (std::size_t i = 0; i < xs.size(); ++i) cv::circle(img, p.px(xs[i], ys[i]), 3, col, cv::FILLED, cv::LINE_AA);
      }
    }
  }
  write_png(png, img);
}

void plot_overlay(const std::string& png, const DiagData& d, const ReplayModel& nominal,
                  const ReplayModel& corrected, const std::vector<char>& mask, const ReplayOptions& o) {
  const int W = 1200, H = 1000;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  text(img, "held out: measured (black), nominal (red), corrected (blue) open-loop predictions", {70, 22}, 0.5);
  // Held-out rows.
  std::vector<std::size_t> rows;
  for (std::size_t k = 0; k < d.rows(); ++k)
    if (mask[k] && d.piece[k] >= 0) rows.push_back(k);
  if (rows.size() < 10) {
    write_png(png, img);
    return;
  }
  // x-y.
  double x0 = 1e18, x1 = -1e18, y0 = 1e18, y1 = -1e18;
  for (auto k : rows) {
    x0 = std::min(x0, d.x[k]);
    x1 = std::max(x1, d.x[k]);
    y0 = std::min(y0, d.y[k]);
    y1 = std::max(y1, d.y[k]);
  }
  const double span = std::max({x1 - x0, y1 - y0, 1.0}) * 1.1;
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  Panel pxy{cv::Rect(370, 50, 460, 460), cx - span / 2, cx + span / 2, cy - span / 2, cy + span / 2};
  frame(img, pxy, "x-y [m], 2 s predictions every 1 s", "x [m]");
  {
    std::vector<double> xs, ys;
    std::size_t prev = rows.front();
    for (auto k : rows) {
      if (k != prev + 1 && k != rows.front()) {
        xs.push_back(NAN);
        ys.push_back(NAN);
      }
      xs.push_back(d.x[k]);
      ys.push_back(d.y[k]);
      prev = k;
    }
    polyline(img, pxy, xs, ys, kMeasured, 1);
  }
  const int len2 = std::max(1, static_cast<int>(std::lround(2.0 / d.dt_s)));
  const int every = std::max(1, static_cast<int>(std::lround(1.0 / d.dt_s)));
  const auto segs = make_segments(d, mask, len2, every);
  std::vector<double> pred(static_cast<std::size_t>(len2) * kPredStride);
  for (const auto& s : segs)
    for (const auto* m : {&nominal, &corrected}) {
      predict_segment(*m, d, s, o, pred.data());
      std::vector<double> xs = {d.x[s.start]}, ys = {d.y[s.start]};
      for (int i = 0; i < len2; ++i) {
        xs.push_back(pred[static_cast<std::size_t>(i) * kPredStride + 3]);
        ys.push_back(pred[static_cast<std::size_t>(i) * kPredStride + 4]);
      }
      polyline(img, pxy, xs, ys, m == &nominal ? kBefore : kAfter, 1);
    }
  // Time series: vx and yaw rate with 1-s-ahead predictions.
  const int len1 = std::max(1, static_cast<int>(std::lround(1.0 / d.dt_s)));
  for (int c : {0, 2}) {
    std::vector<double> ts, meas, pn, pc;
    double lo = 1e18, hi = -1e18;
    for (auto k : rows) {
      ts.push_back(d.t[k]);
      meas.push_back(d.channel(c, k));
      lo = std::min(lo, d.channel(c, k));
      hi = std::max(hi, d.channel(c, k));
      double vn = NAN, vc = NAN;
      if (k >= static_cast<std::size_t>(len1) && d.continuous(k - static_cast<std::size_t>(len1), static_cast<std::size_t>(len1))) {
        const Segment s{k - static_cast<std::size_t>(len1), len1};
        std::vector<double> pr(static_cast<std::size_t>(len1) * kPredStride);
        predict_segment(nominal, d, s, o, pr.data());
        vn = pr[static_cast<std::size_t>(len1 - 1) * kPredStride + static_cast<std::size_t>(c)];
        predict_segment(corrected, d, s, o, pr.data());
        vc = pr[static_cast<std::size_t>(len1 - 1) * kPredStride + static_cast<std::size_t>(c)];
      }
      pn.push_back(vn);
      pc.push_back(vc);
    }
    const double pad = 0.15 * std::max(1e-3, hi - lo);
    Panel p{cv::Rect(70, c == 0 ? 570 : 800, 1080, 160), ts.front(), ts.back(), lo - pad, hi + pad};
    frame(img, p, std::string(kChannelNames[c]) + " [" + kChannelUnits[c] + "], 1 s ahead predictions", "t [s]");
    polyline(img, p, ts, meas, kMeasured, 1);
    polyline(img, p, ts, pn, kBefore, 1);
    polyline(img, p, ts, pc, kAfter, 1);
  }
  write_png(png, img);
}

}  // namespace mppi::diagnose
