#include "diagnose/locate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

namespace mppi::diagnose {

ResidualSeries residual_series(const ReplayModel& model, const PreparedRecording& d, double horizon_s,
                               const ReplayOptions& o) {
  ResidualSeries rs;
  const int len = std::max(1, static_cast<int>(std::lround(horizon_s / d.dt_s)));
  rs.horizon_s = len * d.dt_s;
  for (auto& v : rs.e) v.assign(d.rows(), std::numeric_limits<double>::quiet_NaN());
  std::vector<Segment> segs;
  for (std::size_t k = 0; k + static_cast<std::size_t>(len) < d.rows(); ++k)
    if (d.continuous(k, static_cast<std::size_t>(len))) segs.push_back({k, len});
  std::vector<double> pred(segs.size() * static_cast<std::size_t>(len) * kPredStride);
  predict_segments(model, d, segs, o, pred.data());
  for (std::size_t n = 0; n < segs.size(); ++n) {
    const std::size_t k = segs[n].start;
    const double* p = pred.data() + ((n + 1) * static_cast<std::size_t>(len) - 1) * kPredStride;
    const double h = d.t[k + static_cast<std::size_t>(len)] - d.t[k];
    for (int c = 0; c < kChannels; ++c)
      if (std::isfinite(p[c])) rs.e[c][k] = (d.channel(c, k + static_cast<std::size_t>(len)) - p[c]) / h;
  }
  return rs;
}

std::vector<double> regime_variable(const PreparedRecording& d, int regime) {
  const std::size_t n = d.rows();
  std::vector<double> v(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k > 0 ? k - 1 : k, b = k + 1 < n ? k + 1 : k;
    const double dt = std::max(1e-6, d.t[b] - d.t[a]);
    switch (regime) {
      case 0: v[k] = d.vx[k]; break;
      case 1: v[k] = d.vx[k] * d.r[k]; break;
      case 2: v[k] = (d.vx[b] - d.vx[a]) / dt - d.vy[k] * d.r[k]; break;
      case 3: v[k] = d.steer_over(k); break;
      case 4: v[k] = d.throttle_over(k); break;
      default: v[k] = (d.steer_over(b) - d.steer_over(a)) / dt; break;
    }
  }
  return v;
}

std::vector<BinStat> bin_residual(const std::vector<double>& resid, const std::vector<double>& regime,
                                  const std::vector<char>& mask, int bins, double spi) {
  std::vector<std::size_t> idx;
  for (std::size_t k = 0; k < resid.size(); ++k)
    if (std::isfinite(resid[k]) && (mask.empty() || mask[k])) idx.push_back(k);
  std::vector<BinStat> out;
  if (idx.size() < static_cast<std::size_t>(bins) * 10) return out;
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return regime[a] < regime[b]; });
  for (int b = 0; b < bins; ++b) {
    const std::size_t i0 = idx.size() * static_cast<std::size_t>(b) / static_cast<std::size_t>(bins);
    const std::size_t i1 = idx.size() * static_cast<std::size_t>(b + 1) / static_cast<std::size_t>(bins);
    BinStat s;
    s.lo = regime[idx[i0]];
    s.hi = regime[idx[i1 - 1]];
    s.n = static_cast<int>(i1 - i0);
    double sum = 0, sum2 = 0;
    for (std::size_t i = i0; i < i1; ++i) {
      sum += resid[idx[i]];
      sum2 += resid[idx[i]] * resid[idx[i]];
    }
    s.mean = sum / s.n;
    s.rms = std::sqrt(sum2 / s.n);
    const double sd = std::sqrt(std::max(1e-18, sum2 / s.n - s.mean * s.mean));
    s.z = s.mean / (sd / std::sqrt(std::max(1.0, s.n / spi)));
    out.push_back(s);
  }
  return out;
}

namespace {

// Best single change point of the mean in x[a, b): index and t statistic.
std::pair<std::size_t, double> best_split(const std::vector<double>& x, std::size_t a, std::size_t b,
                                          std::size_t min_len, double spi) {
  std::pair<std::size_t, double> best{0, 0.0};
  if (b - a < 2 * min_len) return best;
  double total = 0, total2 = 0;
  for (std::size_t i = a; i < b; ++i) {
    total += x[i];
    total2 += x[i] * x[i];
  }
  const double n = static_cast<double>(b - a);
  const double var = std::max(1e-18, total2 / n - (total / n) * (total / n));
  double left = 0;
  for (std::size_t i = a; i < b; ++i) {
    left += x[i];
    const std::size_t nl = i + 1 - a;
    if (nl < min_len || b - i - 1 < min_len) continue;
    const double ml = left / nl, mr = (total - left) / (n - nl);
    const double se = std::sqrt(var * spi * (1.0 / nl + 1.0 / (n - nl)));
    const double tstat = std::abs(ml - mr) / se;
    if (tstat > best.second) best = {i + 1, tstat};
  }
  return best;
}

struct PlaceCell {
  double x0, x1, y0, y1;
  BinStat stat;
};
// The cells of a 4 x 4 grid with at least min_rows rows in mask.
std::vector<PlaceCell> place_cells(const PreparedRecording& d, const std::vector<double>& resid, const std::vector<char>& mask,
                                   double spi, int min_rows) {
  constexpr int kCells = 4;
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (std::size_t k = 0; k < resid.size(); ++k)
    if (std::isfinite(resid[k]) && (mask.empty() || mask[k])) {
      x0 = std::min(x0, d.x[k]);
      x1 = std::max(x1, d.x[k]);
      y0 = std::min(y0, d.y[k]);
      y1 = std::max(y1, d.y[k]);
    }
  std::vector<PlaceCell> out;
  if (!(x1 > x0 && y1 > y0)) return out;
  const double wx = (x1 - x0) / kCells, wy = (y1 - y0) / kCells;
  double sum[kCells][kCells] = {}, sum2[kCells][kCells] = {};
  int n[kCells][kCells] = {};
  for (std::size_t k = 0; k < resid.size(); ++k) {
    if (!std::isfinite(resid[k]) || (!mask.empty() && !mask[k])) continue;
    const int i = std::min(kCells - 1, static_cast<int>((d.x[k] - x0) / wx));
    const int j = std::min(kCells - 1, static_cast<int>((d.y[k] - y0) / wy));
    sum[i][j] += resid[k];
    sum2[i][j] += resid[k] * resid[k];
    ++n[i][j];
  }
  for (int i = 0; i < kCells; ++i)
    for (int j = 0; j < kCells; ++j) {
      if (n[i][j] < min_rows) continue;
      PlaceCell c{x0 + i * wx, x0 + (i + 1) * wx, y0 + j * wy, y0 + (j + 1) * wy, {}};
      c.stat.n = n[i][j];
      c.stat.mean = sum[i][j] / n[i][j];
      c.stat.rms = std::sqrt(sum2[i][j] / n[i][j]);
      const double sd = std::sqrt(std::max(1e-18, sum2[i][j] / n[i][j] - c.stat.mean * c.stat.mean));
      c.stat.z = c.stat.mean / (sd / std::sqrt(std::max(1.0, n[i][j] / spi)));
      out.push_back(c);
    }
  return out;
}

std::string range_text(const char* name, double lo, double hi, const char* unit) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%s in [%.3g, %.3g] %s", name, lo, hi, unit);
  return buf;
}

}  // namespace

std::vector<Mismatch> locate(const PreparedRecording& d, const ResidualSeries& res, const std::vector<char>& mask,
                             const LocateOptions& options) {
  const double min_z = options.min_z;
  const int bins = options.bins;
  std::vector<Mismatch> out;
  const double spi = std::max(1.0, res.horizon_s / d.dt_s);  // overlapping predictions are correlated
  std::vector<std::vector<double>> regimes;
  for (int g = 0; g < kRegimes; ++g) regimes.push_back(regime_variable(d, g));
  for (int c = 0; c < kChannels; ++c) {
    const std::string unit = std::string(kChannelUnits[c]) + "/s";
    // Overall bias.
    const auto all = bin_residual(res.e[c], regimes[0], mask, 1, spi);
    if (!all.empty() && std::abs(all[0].z) >= min_z)
      out.push_back({kChannelNames[c], "overall", all[0].mean, all[0].rms, all[0].z, unit});
    const double overall_rms = all.empty() ? 0.0 : all[0].rms;
    // Regime bins that stand out (significant and large against the channel's rms).
    for (int g = 0; g < kRegimes; ++g) {
      for (const auto& b : bin_residual(res.e[c], regimes[static_cast<std::size_t>(g)], mask, bins, spi))
        if (std::abs(b.z) >= min_z && std::abs(b.mean) >= options.min_share_of_rms * overall_rms)
          out.push_back({kChannelNames[c], range_text(kRegimeNames[g], b.lo, b.hi, kRegimeUnits[g]), b.mean,
                         b.rms, b.z, unit});
    }
    // Places: a 4 x 4 grid over the area the masked rows cover; a cell that stands out is where
    // the ground (grip, grade) may differ.
    for (const PlaceCell& cell : place_cells(d, res.e[c], mask, spi, options.min_cell_rows))
      if (std::abs(cell.stat.z) >= min_z && std::abs(cell.stat.mean) >= options.min_share_of_rms * overall_rms) {
        char where[160];
        std::snprintf(where, sizeof where, "place x in [%.3g, %.3g] m, y in [%.3g, %.3g] m", cell.x0, cell.x1, cell.y0,
                      cell.y1);
        out.push_back({kChannelNames[c], where, cell.stat.mean, cell.stat.rms, cell.stat.z, unit});
      }
    // Time windows: binary segmentation of the residual mean, up to 3 levels.
    std::vector<double> x;
    std::vector<std::size_t> rows;
    for (std::size_t k = 0; k < res.e[c].size(); ++k)
      if (std::isfinite(res.e[c][k]) && (mask.empty() || mask[k])) {
        x.push_back(res.e[c][k]);
        rows.push_back(k);
      }
    if (x.size() < 100) continue;
    std::vector<std::size_t> cuts = {0, x.size()};
    const std::size_t min_len = std::max<std::size_t>(50, x.size() / 20);
    for (int level = 0; level < 3; ++level) {
      std::vector<std::size_t> next = {0};
      for (std::size_t s = 0; s + 1 < cuts.size(); ++s) {
        const auto [at, tstat] = best_split(x, cuts[s], cuts[s + 1], min_len, spi);
        if (tstat >= min_z) next.push_back(at);
        next.push_back(cuts[s + 1]);
      }
      if (next.size() == cuts.size()) break;
      cuts = next;
    }
    if (cuts.size() > 2) {
      for (std::size_t s = 0; s + 1 < cuts.size(); ++s) {
        double sum = 0, sum2 = 0;
        for (std::size_t i = cuts[s]; i < cuts[s + 1]; ++i) {
          sum += x[i];
          sum2 += x[i] * x[i];
        }
        const double n = static_cast<double>(cuts[s + 1] - cuts[s]);
        const double mean = sum / n, sd = std::sqrt(std::max(1e-18, sum2 / n - mean * mean));
        const double z = mean / (sd / std::sqrt(std::max(1.0, n / spi)));
        if (std::abs(z) >= min_z)
          out.push_back({kChannelNames[c],
                         range_text("t", d.t[rows[cuts[s]]], d.t[rows[cuts[s + 1] - 1]], "s (change detected)"),
                         mean, std::sqrt(sum2 / n), z, unit});
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const Mismatch& a, const Mismatch& b) { return std::abs(a.z) > std::abs(b.z); });
  return out;
}

}  // namespace mppi::diagnose
