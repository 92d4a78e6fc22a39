#include "diagnose/plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mppi::diagnose {
namespace {

const plot::Rgb kBefore = plot::palette(3), kAfter = plot::palette(0), kMeasured = plot::kBlack;

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

plot::Series line(std::vector<double> x, std::vector<double> y, plot::Rgb colour, const std::string& label,
                  double width_px = 1.2) {
  plot::Series s;
  s.x = std::move(x);
  s.y = std::move(y);
  s.colour = colour;
  s.label = label;
  s.width_px = width_px;
  return s;
}

void add_pieces(plot::Panel& p, const plot::Series& s) {
  for (plot::Series& piece : plot::finite_pieces(s)) p.series.push_back(std::move(piece));
}

// The measured x-y path through the held-out rows, broken where rows are not consecutive; every
// thin-th row, and the ends of each stretch.
plot::Series measured_path(const PreparedRecording& d, const std::vector<std::size_t>& rows, std::size_t thin) {
  plot::Series m = line({}, {}, kMeasured, "measured", 1.0);
  std::size_t prev = rows.front();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::size_t k = rows[i];
    if (k != prev + 1 && i > 0) {
      m.x.push_back(NAN);
      m.y.push_back(NAN);
    }
    if (i % thin == 0 || i + 1 == rows.size() || (i + 1 < rows.size() && rows[i + 1] != k + 1)) {
      m.x.push_back(d.x[k]);
      m.y.push_back(d.y[k]);
    }
    prev = k;
  }
  return m;
}

// The 2-s open-loop x-y predictions of both models, one every 1 s of the held-out rows.
void add_xy_predictions(plot::Panel& pxy, const PreparedRecording& d, const ReplayModel& nominal, const ReplayModel& corrected,
                        const std::vector<char>& mask, const ReplayOptions& o) {
  const int len2 = std::max(1, static_cast<int>(std::lround(2.0 / d.dt_s)));
  const int every = std::max(1, static_cast<int>(std::lround(1.0 / d.dt_s)));
  const int pred_thin = std::max(1, len2 / 20);
  const auto segs = make_segments(d, mask, len2, every);
  std::vector<double> pred(static_cast<std::size_t>(len2) * kPredStride);
  for (const auto& s : segs)
    for (const auto* m : {&nominal, &corrected}) {
      predict_segment(*m, d, s, o, pred.data());
      plot::Series p = line({d.x[s.start]}, {d.y[s.start]}, m == &nominal ? kBefore : kAfter,
                            m == &nominal ? "nominal" : "corrected", 1.0);
      for (int i = 0; i < len2; ++i)
        if ((i + 1) % pred_thin == 0 || i + 1 == len2) {
          p.x.push_back(pred[static_cast<std::size_t>(i) * kPredStride + 3]);
          p.y.push_back(pred[static_cast<std::size_t>(i) * kPredStride + 4]);
        }
      add_pieces(pxy, p);
    }
}

// Channel c over time: measured, and both models' predictions 1 s ahead (len1 rows, predicted
// into pr, len1 * kPredStride values).
plot::Panel channel_panel(int c, const PreparedRecording& d, const std::vector<std::size_t>& rows, std::size_t thin,
                          const ReplayModel& nominal, const ReplayModel& corrected, const ReplayOptions& o, int len1,
                          std::vector<double>& pr) {
  std::vector<double> ts, meas, pn, pc;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::size_t k = rows[i];
    if (i % thin != 0) continue;
    const bool gap = i > 0 && rows[i - 1] + 1 != k;
    if (gap) {  // break the lines between held-out stretches
      ts.push_back(NAN);
      meas.push_back(NAN);
      pn.push_back(NAN);
      pc.push_back(NAN);
    }
    ts.push_back(d.t[k]);
    meas.push_back(d.channel(c, k));
    double vn = NAN, vc = NAN;
    if (k >= static_cast<std::size_t>(len1) &&
        d.continuous(k - static_cast<std::size_t>(len1), static_cast<std::size_t>(len1))) {
      const Segment s{k - static_cast<std::size_t>(len1), len1};
      predict_segment(nominal, d, s, o, pr.data());
      vn = pr[static_cast<std::size_t>(len1 - 1) * kPredStride + static_cast<std::size_t>(c)];
      predict_segment(corrected, d, s, o, pr.data());
      vc = pr[static_cast<std::size_t>(len1 - 1) * kPredStride + static_cast<std::size_t>(c)];
    }
    pn.push_back(vn);
    pc.push_back(vc);
  }
  plot::Panel p;
  p.title = std::string(kChannelNames[c]) + ", 1 s ahead predictions";
  p.x_label = "t [s]";
  p.y_label = std::string(kChannelNames[c]) + " [" + kChannelUnits[c] + "]";
  p.legend = plot::LegendPlace::kNone;
  add_pieces(p, line(ts, meas, kMeasured, "measured", 1.0));
  add_pieces(p, line(ts, pn, kBefore, "nominal", 1.0));
  add_pieces(p, line(ts, pc, kAfter, "corrected", 1.0));
  return p;
}

}  // namespace

plot::Figure residual_vs_regime_figure(const PreparedRecording& d, const ResidualSeries& before, const ResidualSeries& after,
                                       const std::vector<char>& mask) {
  const int regimes[] = {0, 3, 4, 1};
  plot::Figure fig("mean residual (measured - predicted) over " + fmt(before.horizon_s) +
                       " s per regime bin, held-out rows: nominal vs corrected model",
                   4, 330, 260);
  for (int c = 0; c < kChannels; ++c) {
    for (int g = 0; g < 4; ++g) {
      const auto reg = regime_variable(d, regimes[g]);
      const auto b0 = bin_residual(before.e[c], reg, mask, 8, 1.0);
      const auto b1 = bin_residual(after.e[c], reg, mask, 8, 1.0);
      if (b0.empty() || b1.empty()) continue;
      plot::Panel p;
      p.title = std::string(kChannelNames[c]) + " vs " + kRegimeNames[regimes[g]];
      p.x_label = std::string(kRegimeNames[regimes[g]]) + " [" + kRegimeUnits[regimes[g]] + "]";
      p.y_label = std::string(kChannelNames[c]) + " error [" + kChannelUnits[c] + "/s]";
      p.legend = c == 0 && g == 0 ? plot::LegendPlace::kUpperRight : plot::LegendPlace::kNone;
      p.ref_lines.push_back({true, 0.0, "", plot::kGrey, plot::Dash::kSolid, 1.0});
      for (const auto* bs : {&b0, &b1}) {
        std::vector<double> xs, ys;
        for (const auto& b : *bs) {
          xs.push_back(0.5 * (b.lo + b.hi));
          ys.push_back(b.mean);
        }
        plot::Series s = line(xs, ys, bs == &b0 ? kBefore : kAfter, bs == &b0 ? "nominal" : "corrected", 2.0);
        s.marker = plot::Marker::kCircle;
        s.marker_px = 6;
        add_pieces(p, s);
      }
      if (!p.series.empty()) fig.add(p);
    }
  }
  if (fig.panels().empty()) {
    plot::Panel p;
    p.title = "no regime bin has held-out rows";
    p.x_limits = plot::Limits{0, 1};
    p.y_limits = plot::Limits{0, 1};
    fig.add(p);
  }
  return fig;
}

plot::Figure overlay_figure(const PreparedRecording& d, const ReplayModel& nominal, const ReplayModel& corrected,
                            const std::vector<char>& mask, const ReplayOptions& o) {
  plot::Figure fig("held-out part: measured, nominal and corrected open-loop predictions", 1, 1150, 420);
  std::vector<std::size_t> rows;
  for (std::size_t k = 0; k < d.rows(); ++k)
    if (mask[k] && d.piece[k] >= 0) rows.push_back(k);
  if (rows.size() < 10) {
    plot::Panel p;
    p.title = "fewer than 10 held-out rows: nothing to show";
    p.x_limits = plot::Limits{0, 1};
    p.y_limits = plot::Limits{0, 1};
    fig.add(p);
    return fig;
  }
  const std::size_t thin = std::max<std::size_t>(1, rows.size() / 1000);  // keep about a thousand points per series
  // x-y: the measured path (broken where rows are not consecutive) and 2-s predictions every 1 s.
  plot::Panel pxy;
  pxy.title = "x-y, 2 s open-loop predictions every 1 s";
  pxy.x_label = "x [m]";
  pxy.y_label = "y [m]";
  pxy.equal_scale = true;
  add_pieces(pxy, measured_path(d, rows, thin));
  add_xy_predictions(pxy, d, nominal, corrected, mask, o);
  fig.add(pxy);
  // Time series: vx and yaw rate with 1-s-ahead predictions.
  const int len1 = std::max(1, static_cast<int>(std::lround(1.0 / d.dt_s)));
  std::vector<double> pr(static_cast<std::size_t>(len1) * kPredStride);
  for (int c : {0, 2}) fig.add(channel_panel(c, d, rows, thin, nominal, corrected, o, len1, pr));
  return fig;
}

void plot_residual_vs_regime(const std::string& png, const PreparedRecording& d, const ResidualSeries& before,
                             const ResidualSeries& after, const std::vector<char>& mask) {
  residual_vs_regime_figure(d, before, after, mask).write_png(png);
}

void plot_overlay(const std::string& png, const PreparedRecording& d, const ReplayModel& nominal,
                  const ReplayModel& corrected, const std::vector<char>& mask, const ReplayOptions& o) {
  overlay_figure(d, nominal, corrected, mask, o).write_png(png);
}

}  // namespace mppi::diagnose
