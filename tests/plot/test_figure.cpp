// Figures read back from the PNG: a known line at known data coordinates lands where the axes
// frame found in the image says it must (frame located by scanning the pixels, not from the
// layout code); a colour trail has the colour map's colours (oracle: Google's published turbo
// table); a long title stays inside the image; bad data is refused with a clear message.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <limits>
#include <unistd.h>

#include "plot/figure.hpp"
#include "plot/png_image.hpp"

using namespace mppi::plot;

namespace {

std::string temp_png(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("mppi_plot_" + name + "_" + std::to_string(::getpid()) + ".png")).string();
}

// The frame is a thin anti-aliased black line (grey where it straddles two pixels); the grid
// is much lighter (225).
bool dark(const std::array<std::uint8_t, 3>& p) { return p[0] < 180 && p[1] < 180 && p[2] < 180; }
bool near(const std::array<std::uint8_t, 3>& p, std::array<int, 3> want, int tol) {
  for (int i = 0; i < 3; ++i)
    if (std::abs(int(p[i]) - want[i]) > tol) return false;
  return true;
}

// The axes frame: the first dark pixels met going outwards from points inside the axes (left
// and right along `row` from `column`; up from up_from and down from down_from along `column`).
struct Frame {
  int left = -1, right = -1, top = -1, bottom = -1;
};
Frame find_frame(const RgbImage& img, int row, int column, int up_from, int down_from) {
  Frame f;
  for (int c = column; c >= 0 && f.left < 0; --c)
    if (dark(img.at(c, row))) f.left = c;
  for (int c = column; c < img.width && f.right < 0; ++c)
    if (dark(img.at(c, row))) f.right = c;
  for (int r = up_from; r >= 0 && f.top < 0; --r)
    if (dark(img.at(column, r))) f.top = r;
  for (int r = down_from; r < img.height && f.bottom < 0; ++r)
    if (dark(img.at(column, r))) f.bottom = r;
  return f;
}

constexpr std::array<int, 3> kTurbo0{48, 18, 59}, kTurbo128{164, 252, 60}, kTurbo255{122, 4, 3};

}  // namespace

TEST_CASE("figure PNG: lines land at their data coordinates", "[plot]") {
  Figure fig("", 1, 640, 420);
  Panel p;
  p.x_limits = Limits{0, 10};
  p.y_limits = Limits{0, 10};
  p.legend = LegendPlace::kNone;
  Series h;  // y = 2.5, red
  h.x = {0, 10};
  h.y = {2.5, 2.5};
  h.colour = {230, 0, 0};
  h.width_px = 3;
  Series v;  // x = 7.5, blue
  v.x = {7.5, 7.5};
  v.y = {0, 10};
  v.colour = {0, 0, 230};
  v.width_px = 3;
  p.series = {h, v};
  fig.add(p);
  const std::string png = temp_png("lines");
  fig.write_png(png);
  const RgbImage img = read_image_rgb(png);
  std::filesystem::remove(png);
  REQUIRE(img.width == 640);
  REQUIRE(img.height > 400);
  // A row and a column well inside the axes and off the grid lines and the series.
  const Frame f = find_frame(img, img.height / 2 - 7, img.width / 2 - 7, img.height / 2 - 7, img.height / 2 - 7);
  INFO("frame " << f.left << " " << f.right << " " << f.top << " " << f.bottom);
  REQUIRE(f.left > 20);
  REQUIRE(f.right < img.width - 5);
  REQUIRE(f.right - f.left > 400);
  REQUIRE(f.bottom - f.top > 250);
  // y = 2.5 is a quarter of the way up from the bottom edge; x = 7.5 three quarters across.
  const int row = static_cast<int>(std::lround(f.bottom - 0.25 * (f.bottom - f.top)));
  const int col = static_cast<int>(std::lround(f.left + 0.75 * (f.right - f.left)));
  const int probe_col = (f.left + col) / 2, probe_row = (f.top + row) / 2;
  CHECK(near(img.at(probe_col, row), {230, 0, 0}, 30));
  CHECK_FALSE(near(img.at(probe_col, row - 5), {230, 0, 0}, 60));
  CHECK_FALSE(near(img.at(probe_col, row + 5), {230, 0, 0}, 60));
  CHECK(near(img.at(col, probe_row), {0, 0, 230}, 30));
  CHECK_FALSE(near(img.at(col - 5, probe_row), {0, 0, 230}, 60));
  CHECK_FALSE(near(img.at(col + 5, probe_row), {0, 0, 230}, 60));
}

TEST_CASE("figure PNG: a colour trail follows the colour map, a long title fits", "[plot]") {
  const std::string title =
      "gazebo | model autorally-nn, plant single-track | 5 laps [13.95, 11.36, 11.39, 11.41, 11.23] s | crashes 0 | "
      "a title much longer than the figure is wide";
  Figure fig(title, 1, 640, 420);
  Panel p;
  p.x_limits = Limits{-2, 12};
  p.y_limits = Limits{0, 10};
  p.x_label = "x [m]";
  p.y_label = "y [m]";
  ColourTrail t;
  t.value_label = "speed [m/s]";
  t.value_min = 0;
  t.value_max = 10;
  t.width_px = 8;
  for (int i = 0; i <= 1400; ++i) {
    const double x = -2 + 0.01 * i;
    t.x.push_back(x);
    t.y.push_back(5);
    t.value.push_back(x);  // clamped to [0, 10] for the colour
  }
  p.trail = t;
  fig.add(p);
  const std::string png = temp_png("trail");
  fig.write_png(png);
  const RgbImage img = read_image_rgb(png);
  std::filesystem::remove(png);
  // Start above the trail (y = 5) for the top edge, below it for the bottom edge.
  const Frame f = find_frame(img, static_cast<int>(img.height * 0.62), img.width / 3 - 7, static_cast<int>(img.height * 0.4),
                             static_cast<int>(img.height * 0.75));
  INFO("frame " << f.left << " " << f.right << " " << f.top << " " << f.bottom);
  REQUIRE(f.right - f.left > 300);
  const auto at = [&](double x, double y) {
    return img.at(static_cast<int>(std::lround(f.left + (x + 2) / 14 * (f.right - f.left))),
                  static_cast<int>(std::lround(f.bottom - y / 10 * (f.bottom - f.top))));
  };
  CHECK(near(at(-1, 5), kTurbo0, 3));
  INFO("at x = 5: " << int(at(5, 5)[0]) << " " << int(at(5, 5)[1]) << " " << int(at(5, 5)[2]));
  CHECK(near(at(5, 5), kTurbo128, 4));
  CHECK(near(at(11, 5), kTurbo255, 3));
  CHECK(near(at(6, 7), {255, 255, 255}, 0));  // off the trail and the grid: background
  // The title is wrapped, not cut at the image edge: the outermost columns stay white.
  for (int r = 0; r < f.top - 30; ++r)
    for (int c : {0, 1, 2, img.width - 3, img.width - 2, img.width - 1}) CHECK(near(img.at(c, r), {255, 255, 255}, 0));
}

TEST_CASE("figure: bad data is refused with a message naming it", "[plot]") {
  const auto with_series = [](Series s) {
    Figure f("speeds", 1, 400, 300);
    Panel p;
    p.title = "vx";
    p.series = {s};
    f.add(p);
    return f;
  };
  Series empty;
  empty.label = "nominal";
  CHECK_THROWS_WITH(with_series(empty).write_png(temp_png("x")),
                    Catch::Contains("figure 'speeds'") && Catch::Contains("panel 0 'vx'") &&
                        Catch::Contains("series 0 'nominal' is empty"));
  Series nan;
  nan.label = "measured";
  nan.x = {0, 1, 2, 3};
  nan.y = {0, 1, 2, std::numeric_limits<double>::quiet_NaN()};
  CHECK_THROWS_WITH(with_series(nan).validate(), Catch::Contains("'measured'") && Catch::Contains("point 3") &&
                                                     Catch::Contains("non-finite y"));
  Series uneven;
  uneven.x = {0, 1};
  uneven.y = {0};
  CHECK_THROWS_WITH(with_series(uneven).validate(), Catch::Contains("2 x values but 1 y values"));
  Series fine;
  fine.x = {0, 1};
  fine.y = {0, 1};
  CHECK_NOTHROW(with_series(fine).validate());
  CHECK_THROWS_WITH(with_series(fine).write_png("/nonexistent-dir/x.png"),
                    Catch::Contains("/nonexistent-dir/x.png") && Catch::Contains("cannot write"));
  Figure none("nothing", 1, 400, 300);
  CHECK_THROWS_WITH(none.validate(), Catch::Contains("has no panels"));
  Figure bad_limits("limits", 1, 400, 300);
  Panel p;
  p.series = {fine};
  p.y_limits = Limits{1, 1};
  bad_limits.add(p);
  CHECK_THROWS_WITH(bad_limits.validate(), Catch::Contains("y limits"));
}
