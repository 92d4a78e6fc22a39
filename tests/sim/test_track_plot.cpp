// The run plot: size, equal scale with y up, speed colours (oracle: Google's published turbo
// table), crash markers and barrier pipes, read back from the PNG.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <unistd.h>

#include "plot/layout.hpp"
#include "sim/track.hpp"
#include "sim/track_plot.hpp"
#include "test_data.hpp"

using namespace mppi::sim;

namespace {
// Turbo colour map (A. Mikhailov, Google, 2019), entries 0, 128 and 255 of the 256-entry
// table, times 255: (0.18995,0.07176,0.23217), (0.64362,0.98999,0.23356), (0.47960,0.01583,0.01055).
constexpr std::array<int, 3> kTurbo0{48, 18, 59};
constexpr std::array<int, 3> kTurbo128{164, 252, 60};
constexpr std::array<int, 3> kTurbo255{122, 4, 3};

void check_colour(const std::array<std::uint8_t, 3>& got, const std::array<int, 3>& want, int tol = 1) {
  for (int i = 0; i < 3; ++i) CHECK(std::abs(int(got[i]) - want[i]) <= tol);
}
}  // namespace

TEST_CASE("speed colours follow the turbo table", "[sim]") {
  const std::array<std::uint8_t, 3> lo = speed_colour_rgb(2.0, 2.0, 8.0);
  const std::array<std::uint8_t, 3> mid = speed_colour_rgb(5.0, 2.0, 8.0);   // 127.5 -> 128
  const std::array<std::uint8_t, 3> hi = speed_colour_rgb(9.0, 2.0, 8.0);    // clamped
  check_colour(lo, kTurbo0);
  check_colour(mid, kTurbo128);
  check_colour(hi, kTurbo255);
}

TEST_CASE("track plot: size, equal scale, y up, path coloured by speed, crashes in red", "[sim][plot]") {
  TrackOptions o;
  o.data_dir = mppi::test::data_path("");
  const Track t = Track::load("gazebo", o);

  // The path follows the centreline for one lap in three speed bands: 2, 5, 8 m/s.
  std::vector<PathSample> path;
  const std::size_t n = t.centreline().size();
  for (std::size_t i = 0; i <= n; ++i) {
    const Vec2 p = t.centreline()[i % n];
    const float v = i < n / 3 ? 2.f : (i < 2 * n / 3 ? 5.f : 8.f);
    path.push_back({static_cast<float>(p.x), static_cast<float>(p.y), v});
  }
  const Vec2 crash = t.centreline()[n / 2 + 5];
  const std::string png = (std::filesystem::temp_directory_path() /
                           ("mppi_sim_test_plot_" + std::to_string(::getpid()) + ".png")).string();
  std::filesystem::remove(png);
  const std::vector<std::pair<float, float>> crashes{{static_cast<float>(crash.x), static_cast<float>(crash.y)}};
  plot_track_run(png, t, path, crashes, "gazebo - single_track\nlaps 1: 12.34 s");

  const RgbImage img = read_image_rgb(png);
  std::filesystem::remove(png);
  const mppi::plot::FigureLayout layout =
      mppi::plot::layout_figure(track_run_figure(t, path, crashes, "gazebo - single_track\nlaps 1: 12.34 s"));
  CHECK(img.width == 1000);
  CHECK(img.height == layout.height_px);
  // Same scale in x and y, and y up; the whole track inside the axes.
  const Bounds b = t.bounds();
  const auto [c0, r0] = layout.to_pixel(0, b.x_min, b.y_max);
  const auto [c1, r1] = layout.to_pixel(0, b.x_max, b.y_min);
  CHECK((c1 - c0) / (b.x_max - b.x_min) == Approx((r1 - r0) / (b.y_max - b.y_min)).epsilon(1e-6));
  CHECK(r1 > r0);  // lower y = further down the image
  const mppi::plot::PixelRect& axes = layout.panels[0].axes;
  CHECK(c0 >= axes.left);
  CHECK(c1 <= axes.right());
  CHECK(r0 >= axes.top);
  CHECK(r1 <= axes.bottom());
  // Bands: middle sample of each, away from the band edges and the crash mark.
  const auto pixel_at = [&](std::size_t i) {
    const auto [c, r] = layout.to_pixel(0, t.centreline()[i].x, t.centreline()[i].y);
    return img.at(static_cast<int>(std::lround(c)), static_cast<int>(std::lround(r)));
  };
  check_colour(pixel_at(n / 6), kTurbo0, 3);
  check_colour(pixel_at(n / 3 + n / 10), kTurbo128, 3);
  check_colour(pixel_at(5 * n / 6), kTurbo255, 3);
  // Crash marker: red at its centre (drawn over the path).
  const auto [cc, cr] = layout.to_pixel(0, crash.x, crash.y);
  check_colour(img.at(static_cast<int>(std::lround(cc)), static_cast<int>(std::lround(cr))), {230, 0, 0}, 3);
  // Barrier pipes are drawn: the pixel at a pipe centre is dark grey.
  const Vec2 pipe = t.barriers()[1].centre[10];
  const auto [pc, pr] = layout.to_pixel(0, pipe.x, pipe.y);
  const auto grey = img.at(static_cast<int>(std::lround(pc)), static_cast<int>(std::lround(pr)));
  CHECK(grey[0] < 120);
  CHECK(grey[0] == grey[1]);
  // The bottom-right corner of the image stays background white.
  check_colour(img.at(img.width - 2, img.height - 2), {255, 255, 255});
  CHECK_THROWS_WITH(plot_track_run("/nonexistent-dir/plot.png", t, path, {}, "x"),
                    Catch::Contains("/nonexistent-dir/plot.png") && Catch::Contains("cannot write"));
}
