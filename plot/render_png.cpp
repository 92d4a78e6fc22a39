// Figure::write_png: draws the laid-out figure with PLplot's Cairo PNG device. PLplot keeps
// global state, so one figure is drawn at a time (a mutex), each on a fresh stream.
#include <plplot.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>

#include "base/error.hpp"
#include "plot/figure.hpp"
#include "plot/layout.hpp"

namespace mppi::plot {

namespace {

constexpr int kScratchColour = 15;  // cmap0 entry re-set to each drawing colour

// PLplot's text escape character is '#'; a literal '#' is written "##".
std::string escaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    out += c;
    if (c == '#') out += '#';
  }
  return out;
}

class Canvas {
 public:
  Canvas(const FigureLayout& layout) : layout_(layout) {
    double xmin, xmax, ymin, ymax;
    plgspa(&xmin, &xmax, &ymin, &ymax);
    px_per_mm_ = layout.width_px / (xmax - xmin);
  }

  void colour(Rgb c) {
    plscol0(kScratchColour, c.r, c.g, c.b);
    plcol0(kScratchColour);
  }
  void width(double px) { plwidth(px); }
  void dash(Dash d, double width_px) {
    if (d == Dash::kSolid) {
      plstyl(0, nullptr, nullptr);
      return;
    }
    // Lengths in micrometres of the page.
    const double on_px = d == Dash::kDashed ? 7.0 : std::max(1.5, width_px), off_px = d == Dash::kDashed ? 4.0 : 3.0;
    const PLINT mark = static_cast<PLINT>(std::lround(1000.0 * on_px / px_per_mm_));
    const PLINT space = static_cast<PLINT>(std::lround(1000.0 * off_px / px_per_mm_));
    plstyl(1, &mark, &space);
  }
  // Text size: PLplot's character height is about 0.8 of the font's em size.
  void text_size(double em_px) { plschr(0.8 * em_px / px_per_mm_, 1.0); }

  // Viewport in pixels (row 0 at the top) with the given data window.
  void axes(const PixelRect& r, double x0, double x1, double y0, double y1) {
    plvpor(r.left / layout_.width_px, r.right() / layout_.width_px, 1.0 - r.bottom() / layout_.height_px,
           1.0 - r.top / layout_.height_px);
    plwind(x0, x1, y0, y1);
  }
  // The whole page, in pixel coordinates (y up: row r is y = height - r).
  void page() { axes({0, 0, static_cast<double>(layout_.width_px), static_cast<double>(layout_.height_px)}, 0,
                     layout_.width_px, 0, layout_.height_px); }
  // Text centred vertically on row `row`; just 0 = left, 0.5 = centre, 1 = right; vertical = rotated 90 degrees.
  void text(double col, double row, double just, const std::string& s, double em_px, Rgb c, bool vertical = false) {
    page();
    text_size(em_px);
    colour(c);
    const double y = layout_.height_px - row;
    plptex(col, y, vertical ? 0.0 : 1.0, vertical ? 1.0 : 0.0, just, escaped(s).c_str());
  }
  void rect_fill(double col0, double row0, double col1, double row1, Rgb c) {
    page();
    colour(c);
    const double h = layout_.height_px;
    PLFLT x[4] = {col0, col1, col1, col0}, y[4] = {h - row0, h - row0, h - row1, h - row1};
    plfill(4, x, y);
  }
  void rect_line(double col0, double row0, double col1, double row1, Rgb c, double w) {
    page();
    colour(c);
    width(w);
    dash(Dash::kSolid, w);
    const double h = layout_.height_px;
    PLFLT x[5] = {col0, col1, col1, col0, col0}, y[5] = {h - row0, h - row0, h - row1, h - row1, h - row0};
    plline(5, x, y);
  }
  void line_px(double c0, double r0, double c1, double r1, Rgb c, double w, Dash d) {
    page();
    colour(c);
    width(w);
    dash(d, w);
    pljoin(c0, layout_.height_px - r0, c1, layout_.height_px - r1);
    dash(Dash::kSolid, w);
  }

 private:
  const FigureLayout& layout_;
  double px_per_mm_ = 1.0;
};

struct LabelSteps {
  double x_step = 1, y_step = 1;
};

void label_callback(PLINT axis, PLFLT value, char* label, PLINT length, PLPointer data) {
  const auto* steps = static_cast<const LabelSteps*>(data);
  const std::string s = tick_label(value, axis == PL_X_AXIS ? steps->x_step : steps->y_step);
  std::snprintf(label, static_cast<std::size_t>(length), "%s", s.c_str());
}

int minor_ticks(double step) {
  const double m = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  return std::lround(m) == 2 ? 4 : 5;
}

void draw_markers(Canvas& cv, const PanelLayout& l, const Series& s) {
  const double ux = (l.x.hi - l.x.lo) / l.axes.width, uy = (l.y.hi - l.y.lo) / l.axes.height;  // data per px
  const double r = 0.5 * s.marker_px;
  cv.colour(s.colour);
  cv.dash(Dash::kSolid, 1);
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    const double x = s.x[i], y = s.y[i];
    if (x < l.x.lo || x > l.x.hi || y < l.y.lo || y > l.y.hi) continue;
    switch (s.marker) {
      case Marker::kCircle: {
        PLFLT px[16], py[16];
        for (int k = 0; k < 16; ++k) {
          px[k] = x + r * ux * std::cos(k * M_PI / 8);
          py[k] = y + r * uy * std::sin(k * M_PI / 8);
        }
        plfill(16, px, py);
        break;
      }
      case Marker::kSquare: {
        PLFLT px[4] = {x - r * ux, x + r * ux, x + r * ux, x - r * ux}, py[4] = {y - r * uy, y - r * uy, y + r * uy, y + r * uy};
        plfill(4, px, py);
        break;
      }
      case Marker::kCross:
        cv.width(std::max(2.0, 0.3 * s.marker_px));
        pljoin(x - r * ux, y - r * uy, x + r * ux, y + r * uy);
        pljoin(x - r * ux, y + r * uy, x + r * ux, y - r * uy);
        break;
      case Marker::kNone:
        break;
    }
  }
}

struct LegendEntry {
  std::string label;
  Rgb colour;
  double width_px;
  Dash dash;
  Marker marker;
};

void draw_legend(Canvas& cv, const PanelLayout& l, const Panel& panel) {
  if (panel.legend == LegendPlace::kNone) return;
  std::vector<LegendEntry> entries;
  for (const Series& s : panel.series)
    if (!s.label.empty() && std::none_of(entries.begin(), entries.end(), [&](const LegendEntry& e) { return e.label == s.label; }))
      entries.push_back({s.label, s.colour, s.width_px, s.dash, s.marker});
  for (const RefLine& r : panel.ref_lines)
    if (!r.label.empty()) entries.push_back({r.label, r.colour, r.width_px, r.dash, Marker::kNone});
  if (entries.empty()) return;
  const double line_h = std::round(1.45 * kLegendPx), sample_w = 26, pad = 6;
  double text_w = 0;
  for (const auto& e : entries) text_w = std::max(text_w, text_width_px(e.label, kLegendPx));
  const double w = pad + sample_w + 6 + text_w + pad, h = pad + line_h * entries.size() + pad - 4;
  const bool right = panel.legend == LegendPlace::kUpperRight || panel.legend == LegendPlace::kLowerRight;
  const bool upper = panel.legend == LegendPlace::kUpperRight || panel.legend == LegendPlace::kUpperLeft;
  const double c0 = right ? l.axes.right() - 8 - w : l.axes.left + 8;
  const double r0 = upper ? l.axes.top + 8 : l.axes.bottom() - 8 - h;
  cv.rect_fill(c0, r0, c0 + w, r0 + h, kWhite);
  cv.rect_line(c0, r0, c0 + w, r0 + h, kLightGrey, 1);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const auto& e = entries[i];
    const double row = r0 + pad + line_h * (i + 0.5) - 2;
    if (e.width_px > 0) cv.line_px(c0 + pad, row, c0 + pad + sample_w, row, e.colour, std::max(1.5, e.width_px), e.dash);
    if (e.marker != Marker::kNone) {
      const double mc = c0 + pad + 0.5 * sample_w;
      if (e.marker == Marker::kCross) {
        cv.line_px(mc - 4, row - 4, mc + 4, row + 4, e.colour, 2, Dash::kSolid);
        cv.line_px(mc - 4, row + 4, mc + 4, row - 4, e.colour, 2, Dash::kSolid);
      } else {
        cv.rect_fill(mc - 3, row - 3, mc + 3, row + 3, e.colour);
      }
    }
    cv.text(c0 + pad + sample_w + 6, row, 0.0, e.label, kLegendPx, kBlack);
  }
}

void draw_colour_bar(Canvas& cv, const PanelLayout& l, const ColourTrail& t, LabelSteps& steps) {
  const PixelRect& b = l.colour_bar;
  const NiceAxis& a = l.colour_axis;
  cv.axes(b, 0, 1, a.lo, a.hi);
  constexpr int kBands = 256;
  for (int i = 0; i < kBands; ++i) {
    const double v0 = a.lo + (a.hi - a.lo) * i / kBands, v1 = a.lo + (a.hi - a.lo) * (i + 1) / kBands;
    cv.colour(colour_map_rgb(t.map, (i + 0.5) / kBands));
    PLFLT x[4] = {0, 1, 1, 0}, y[4] = {v0, v0, v1, v1};
    plfill(4, x, y);
  }
  cv.colour(kBlack);
  cv.width(1);
  cv.text_size(kTickPx);
  steps.y_step = a.step;
  cv.axes(b, 0, 1, a.lo, a.hi);
  plbox("bc", 0, 0, "bcmtv", a.step, 0);
  double label_w = 0;
  for (double v : a.ticks) label_w = std::max(label_w, text_width_px(tick_label(v, a.step), kTickPx));
  if (!t.value_label.empty())
    cv.text(b.right() + 6 + label_w + 8 + 0.5 * kLabelPx, b.top + 0.5 * b.height, 0.5, t.value_label, kLabelPx, kBlack, true);
}

void draw_panel(Canvas& cv, const PanelLayout& l, const Panel& panel) {
  LabelSteps steps{l.x.step, l.y.step};
  plslabelfunc(label_callback, &steps);
  // Grid under everything.
  cv.axes(l.axes, l.x.lo, l.x.hi, l.y.lo, l.y.hi);
  cv.colour(kGridGrey);
  cv.width(1);
  cv.dash(Dash::kSolid, 1);
  plbox("g", l.x.step, 0, "g", l.y.step, 0);
  for (const RefLine& r : panel.ref_lines) {
    cv.colour(r.colour);
    cv.width(r.width_px);
    cv.dash(r.dash, r.width_px);
    if (r.horizontal)
      pljoin(l.x.lo, r.at, l.x.hi, r.at);
    else
      pljoin(r.at, l.y.lo, r.at, l.y.hi);
  }
  cv.dash(Dash::kSolid, 1);
  // Lines, then the colour trail, then scatter-only series on top.
  for (const Series& s : panel.series) {
    if (s.width_px == 0) continue;
    if (s.x.size() > 1) {
      cv.colour(s.colour);
      cv.width(s.width_px);
      cv.dash(s.dash, s.width_px);
      plline(static_cast<PLINT>(s.x.size()), s.x.data(), s.y.data());
      cv.dash(Dash::kSolid, 1);
    }
    if (s.marker != Marker::kNone) draw_markers(cv, l, s);
  }
  if (panel.trail) {
    // Each segment a filled band (butt ends, 0.5 px longer at each end to close the joins):
    // stroked lines would get caps, and the next segment's cap would paint over this one.
    const ColourTrail& t = *panel.trail;
    const double ux = (l.x.hi - l.x.lo) / l.axes.width, uy = (l.y.hi - l.y.lo) / l.axes.height;  // data per px
    for (std::size_t i = 0; i + 1 < t.x.size(); ++i) {
      const double dx = (t.x[i + 1] - t.x[i]) / ux, dy = (t.y[i + 1] - t.y[i]) / uy, len = std::hypot(dx, dy);
      if (len < 1e-9) continue;
      const double ex = 0.5 * dx / len, ey = 0.5 * dy / len;                                  // 0.5 px along
      const double nx = -dy / len * 0.5 * t.width_px, ny = dx / len * 0.5 * t.width_px;       // half width across
      const double ax = t.x[i] - ex * ux, ay = t.y[i] - ey * uy, bx = t.x[i + 1] + ex * ux, by = t.y[i + 1] + ey * uy;
      PLFLT px[4] = {ax + nx * ux, bx + nx * ux, bx - nx * ux, ax - nx * ux};
      PLFLT py[4] = {ay + ny * uy, by + ny * uy, by - ny * uy, ay - ny * uy};
      cv.colour(colour_for_value(t.map, 0.5 * (t.value[i] + t.value[i + 1]), l.colour_axis.lo, l.colour_axis.hi));
      plfill(4, px, py);
    }
  }
  for (const Series& s : panel.series)
    if (s.width_px == 0) draw_markers(cv, l, s);
  // Frame, ticks and tick labels on top of the data.
  cv.axes(l.axes, l.x.lo, l.x.hi, l.y.lo, l.y.hi);
  cv.colour(kBlack);
  cv.width(1);
  cv.text_size(kTickPx);
  const std::string y_opts = panel.right_axis ? "bcnmstv" : "bcnstv";
  plbox("bcnst", l.x.step, minor_ticks(l.x.step), y_opts.c_str(), l.y.step, minor_ticks(l.y.step));
  // Labels and title.
  if (!panel.x_label.empty())
    cv.text(l.axes.left + 0.5 * l.axes.width, l.axes.bottom() + 8 + kTickPx + 8 + 0.6 * kLabelPx, 0.5, panel.x_label,
            kLabelPx, kBlack);
  if (!panel.y_label.empty())
    cv.text(l.cell.left + 10 + 0.6 * kLabelPx, l.axes.top + 0.5 * l.axes.height, 0.5, panel.y_label, kLabelPx, kBlack, true);
  for (std::size_t i = 0; i < l.title.lines.size(); ++i)
    cv.text(l.axes.left + 0.5 * l.axes.width, l.cell.top + 6 + l.title.line_px * (i + 0.5), 0.5, l.title.lines[i],
            l.title.size_px, kBlack);
  draw_legend(cv, l, panel);
  if (panel.trail) draw_colour_bar(cv, l, *panel.trail, steps);
}

std::mutex& plplot_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

void Figure::write_png(const std::string& path) const {
  const FigureLayout layout = layout_figure(*this);
  {
    // PLplot ends the program on an unopenable file; check first.
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw Error(path + ": cannot write the PNG (" + std::strerror(errno) + ")");
    std::fclose(f);
  }
  std::lock_guard<std::mutex> lock(plplot_mutex());
  PLINT stream = 0;
  plmkstrm(&stream);
  if (stream < 0) throw Error(path + ": PLplot has no free stream");
  plsdev("pngcairo");
  plsfnam(path.c_str());
  plspage(72, 72, layout.width_px, layout.height_px, 0, 0);
  plscolbg(255, 255, 255);
  plscmap0n(16);
  plinit();
  pladv(0);
  {
    Canvas cv(layout);
    for (std::size_t i = 0; i < layout.title.lines.size(); ++i)
      cv.text(0.5 * layout.width_px, 6 + layout.title.line_px * (i + 0.5), 0.5, layout.title.lines[i],
              layout.title.size_px, kBlack);
    for (std::size_t p = 0; p < panels_.size(); ++p) draw_panel(cv, layout.panels[p], panels_[p]);
  }
  plend1();
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) == 0 || ec) throw Error(path + ": PLplot wrote no PNG");
}

}  // namespace mppi::plot
