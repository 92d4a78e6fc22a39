#include "plot/layout.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "base/error.hpp"

namespace mppi::plot {

namespace {

constexpr double kLabelLinePx = 1.35 * kLabelPx;
constexpr double kOuterPadPx = 10;
constexpr double kColourBarWidthPx = 16;
constexpr double kPxPerTickX = 90, kPxPerTickY = 55;  // about one major tick per this many pixels

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return !(hi >= lo); }
};

int max_intervals(double axis_px, double px_per_tick) { return std::clamp(static_cast<int>(axis_px / px_per_tick), 3, 10); }

double widest_tick_label(const NiceAxis& a) {
  double w = 0;
  for (double t : a.ticks) w = std::max(w, text_width_px(tick_label(t, a.step), kTickPx));
  return w;
}

std::vector<std::string> split_words(const std::string& text) {
  // Break after " | " and ", " first (they separate the parts of a title), then at spaces.
  std::vector<std::string> words;
  std::string cur;
  for (char c : text) {
    cur += c;
    if (c == ' ') {
      words.push_back(cur);
      cur.clear();
    }
  }
  if (!cur.empty()) words.push_back(cur);
  return words;
}

std::string trim(std::string s) {
  // Also a " |" left at the end of a line by a break after a part.
  while (!s.empty() && (s.back() == ' ' || (s.back() == '|' && s.size() > 1 && s[s.size() - 2] == ' '))) s.pop_back();
  while (!s.empty() && s.front() == ' ') s.erase(s.begin());
  return s;
}

}  // namespace

double text_width_px(const std::string& text, double size_px) {
  // DejaVu Sans as PLplot's Cairo device draws it at this size, in em (measured on rendered
  // strings): digits 0.70, lower case 0.64, capitals 0.81, m / w 1.05, narrow letters and
  // punctuation 0.28-0.42; plus 4 % to be safe. UTF-8 continuation bytes add nothing.
  double em = 0;
  for (unsigned char c : text) {
    if ((c & 0xC0) == 0x80) continue;
    if (c == 'i' || c == 'l' || c == 'j' || c == '|' || c == '\'' || c == '!')
      em += 0.30;
    else if (c == ' ' || c == '.' || c == ',' || c == ':' || c == ';')
      em += 0.35;
    else if (c == 'f' || c == 't' || c == 'r' || c == '(' || c == ')' || c == '[' || c == ']' || c == '-' || c == '/')
      em += 0.42;
    else if (c == 'm' || c == 'w' || c == 'M' || c == 'W')
      em += 1.05;
    else if (c >= 'A' && c <= 'Z')
      em += 0.81;
    else if (c >= '0' && c <= '9')
      em += 0.70;
    else
      em += 0.64;
  }
  return 1.04 * em * size_px;
}

TextBlock fit_text(const std::string& text, double width_px, double size_px, int max_lines) {
  TextBlock block;
  std::vector<std::string> paragraphs;
  {
    std::stringstream ss(text);
    std::string line;
    while (std::getline(ss, line)) paragraphs.push_back(line);
  }
  for (double size = size_px; size >= 0.7 * size_px - 1e-9; size -= 0.05 * size_px) {
    block.lines.clear();
    block.size_px = size;
    block.line_px = std::round(1.3 * size);
    bool words_fit = true;
    for (const std::string& para : paragraphs) {
      // Parts separated by " | " stay whole where they fit on a line; longer ones break at spaces.
      std::vector<std::string> parts;
      for (std::size_t from = 0;;) {
        const std::size_t bar = para.find(" | ", from);
        parts.push_back(para.substr(from, bar == std::string::npos ? std::string::npos : bar + 3 - from));
        if (bar == std::string::npos) break;
        from = bar + 3;
      }
      std::string cur;
      for (const std::string& part : parts) {
        if (text_width_px(trim(cur + part), size) <= width_px) {
          cur += part;
          continue;
        }
        if (!cur.empty() && text_width_px(trim(part), size) <= width_px) {
          block.lines.push_back(trim(cur));
          cur = part;
          continue;
        }
        for (const std::string& w : split_words(part)) {
          if (!cur.empty() && text_width_px(trim(cur + w), size) > width_px) {
            block.lines.push_back(trim(cur));
            cur.clear();
          }
          if (text_width_px(trim(w), size) > width_px) words_fit = false;
          cur += w;
        }
      }
      block.lines.push_back(trim(cur));
    }
    if (words_fit && static_cast<int>(block.lines.size()) <= std::max<int>(max_lines, paragraphs.size())) return block;
  }
  return block;  // the smallest size; a line may still be too long
}

std::pair<double, double> FigureLayout::to_pixel(std::size_t p, double x, double y) const {
  const PanelLayout& l = panels.at(p);
  return {l.axes.left + (x - l.x.lo) / (l.x.hi - l.x.lo) * l.axes.width,
          l.axes.bottom() - (y - l.y.lo) / (l.y.hi - l.y.lo) * l.axes.height};
}

FigureLayout layout_figure(const Figure& figure) {
  figure.validate();
  FigureLayout out;
  const int columns = std::min<int>(figure.columns(), static_cast<int>(figure.panels().size()));
  const int rows = static_cast<int>((figure.panels().size() + columns - 1) / columns);
  out.width_px = columns * figure.panel_width_px();
  out.title = fit_text(figure.title(), out.width_px - 2 * kOuterPadPx, kFigureTitlePx);
  const double title_band = figure.title().empty() ? 4 : 10 + out.title.line_px * out.title.lines.size();
  out.height_px = static_cast<int>(std::ceil(title_band)) + rows * figure.panel_height_px();

  for (std::size_t p = 0; p < figure.panels().size(); ++p) {
    const Panel& panel = figure.panels()[p];
    PanelLayout l;
    const int c = static_cast<int>(p) % columns, r = static_cast<int>(p) / columns;
    l.cell = {static_cast<double>(c * figure.panel_width_px()), title_band + r * figure.panel_height_px(),
              static_cast<double>(figure.panel_width_px()), static_cast<double>(figure.panel_height_px())};

    // Data ranges.
    Range xr, yr;
    for (const Series& s : panel.series) {
      for (double v : s.x) xr.add(v);
      for (double v : s.y) yr.add(v);
    }
    if (panel.trail) {
      for (double v : panel.trail->x) xr.add(v);
      for (double v : panel.trail->y) yr.add(v);
    }
    for (const RefLine& rl : panel.ref_lines) (rl.horizontal ? yr : xr).add(rl.at);
    if (panel.x_limits) xr = {panel.x_limits->lo, panel.x_limits->hi};
    if (panel.y_limits) yr = {panel.y_limits->lo, panel.y_limits->hi};
    if (xr.empty()) xr = {0, 1};
    if (yr.empty()) yr = {0, 1};

    // Colour scale.
    if (panel.trail) {
      l.has_colour_bar = true;
      double vmin = panel.trail->value_min, vmax = panel.trail->value_max;
      if (!(vmax > vmin)) {
        const auto [mn, mx] = std::minmax_element(panel.trail->value.begin(), panel.trail->value.end());
        vmin = *mn;
        vmax = *mx;
        if (!(vmax > vmin)) vmax = vmin + 1.0;
      }
      l.colour_axis = ticks_inside(vmin, vmax, 6);
    }

    // Title, then margins from the tick labels (two passes: the ticks depend on the axes' size).
    l.title = fit_text(panel.title, l.cell.width - 2 * kOuterPadPx, kPanelTitlePx, 2);
    const double top = panel.title.empty() ? 14 : 10 + l.title.line_px * l.title.lines.size();
    const double bottom = 8 + kTickPx + 8 + (panel.x_label.empty() ? 0 : kLabelLinePx) + 8;
    double axes_w = l.cell.width * 0.8, axes_h = l.cell.height - top - bottom;
    for (int pass = 0; pass < 2; ++pass) {
      if (panel.equal_scale) {
        const double pad = 0.03 * std::max(xr.hi - xr.lo, yr.hi - yr.lo);
        const double xs = xr.hi - xr.lo + 2 * pad, ys = yr.hi - yr.lo + 2 * pad;
        const double scale = std::max(xs / axes_w, ys / axes_h);  // data units per pixel
        const double cx = 0.5 * (xr.lo + xr.hi), cy = 0.5 * (yr.lo + yr.hi);
        l.x = ticks_inside(cx - 0.5 * scale * axes_w, cx + 0.5 * scale * axes_w, max_intervals(axes_w, kPxPerTickX));
        l.y = ticks_inside(cy - 0.5 * scale * axes_h, cy + 0.5 * scale * axes_h, max_intervals(axes_h, kPxPerTickX));
      } else {
        l.x = panel.x_limits ? ticks_inside(xr.lo, xr.hi, max_intervals(axes_w, kPxPerTickX)) : nice_axis(xr.lo, xr.hi, max_intervals(axes_w, kPxPerTickX));
        l.y = panel.y_limits ? ticks_inside(yr.lo, yr.hi, max_intervals(axes_h, kPxPerTickY)) : nice_axis(yr.lo, yr.hi, max_intervals(axes_h, kPxPerTickY));
      }
      const double y_labels = std::max(widest_tick_label(l.y), text_width_px("0.0", kTickPx));
      const double left = kOuterPadPx + (panel.y_label.empty() ? 0 : kLabelLinePx + 4) + y_labels + 8;
      double right = kOuterPadPx + 8;
      if (panel.right_axis) right += y_labels + 8;
      if (l.has_colour_bar)
        right += 14 + kColourBarWidthPx + 6 + widest_tick_label(l.colour_axis) + 8 + kLabelLinePx;
      axes_w = l.cell.width - left - right;
      axes_h = l.cell.height - top - bottom;
      if (axes_w < 40 || axes_h < 40)
        throw Error("figure '" + figure.title() + "', panel '" + panel.title + "': panel cell too small for its labels");
      l.axes = {l.cell.left + left, l.cell.top + top, axes_w, axes_h};
    }
    if (l.has_colour_bar) {
      const double bar_left = l.axes.right() + (panel.right_axis ? widest_tick_label(l.y) + 16 : 0) + 14;
      const double bar_h = std::min(l.axes.height, std::max(120.0, 0.8 * l.axes.height));
      l.colour_bar = {bar_left, l.axes.top + 0.5 * (l.axes.height - bar_h), kColourBarWidthPx, bar_h};
    }
    out.panels.push_back(l);
  }
  return out;
}

}  // namespace mppi::plot

namespace mppi::plot {

int Figure::panel_height_for_aspect(int panel_width_px, double data_width_over_height, bool colour_bar) {
  if (!(data_width_over_height > 0) || !std::isfinite(data_width_over_height))
    throw Error("panel_height_for_aspect: aspect " + std::to_string(data_width_over_height) + " is not positive");
  // The margins layout_figure gives a panel with a one-line title, axis labels and short ticks.
  const double top = 10 + std::round(1.3 * kPanelTitlePx), bottom = 8 + kTickPx + 8 + kLabelLinePx + 8;
  const double left = kOuterPadPx + kLabelLinePx + 4 + text_width_px("-100", kTickPx) + 8;
  double right = kOuterPadPx + 8;
  if (colour_bar) right += 14 + kColourBarWidthPx + 6 + text_width_px("10.0", kTickPx) + 8 + kLabelLinePx;
  const double axes_w = panel_width_px - left - right;
  return static_cast<int>(std::ceil(top + bottom + axes_w / data_width_over_height));
}

}  // namespace mppi::plot
