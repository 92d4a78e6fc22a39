// A figure read back from JSON (plot/figure_from_json.hpp): figure_to_json's output reads back
// as the same figure, defaults fill what a script leaves out, and bad values are named.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "base/error.hpp"
#include "plot/figure_from_json.hpp"
#include "plot/figure_json.hpp"

using namespace mppi::plot;
using Catch::Matchers::Contains;

TEST_CASE("figure JSON: figure_to_json's figure reads back with its data, styles and limits", "[plot]") {
  Figure figure("speeds", 2, 500, 300);
  Panel panel;
  panel.title = "lap";
  panel.x_label = "t [s]";
  panel.y_label = "v [m/s]";
  panel.series.push_back({{0, 1, 2}, {3, 4, 5}, "run", palette(1), 12.0, Dash::kDashed, Marker::kSquare, 5.0});
  panel.ref_lines.push_back({true, 4.5, "target", kGrey, Dash::kDotted, 1.0});
  panel.legend = LegendPlace::kLowerLeft;
  figure.add(panel);

  const Figure back = figure_from_json(nlohmann::json::parse(figure_to_json(figure).dump()));
  CHECK(back.title() == "speeds");
  CHECK(back.columns() == 1);  // figure_to_json writes the columns in use
  CHECK(back.panel_width_px() == 500);
  REQUIRE(back.panels().size() == 1);
  const Panel& p = back.panels()[0];
  CHECK(p.x_label == "t [s]");
  CHECK(p.legend == LegendPlace::kLowerLeft);
  REQUIRE(p.series.size() == 1);
  CHECK(p.series[0].y == std::vector<double>{3, 4, 5});
  CHECK(p.series[0].colour == palette(1));
  CHECK(p.series[0].width_px == 12.0);
  CHECK(p.series[0].dash == Dash::kDashed);
  CHECK(p.series[0].marker == Marker::kSquare);
  REQUIRE(p.ref_lines.size() == 1);
  CHECK(p.ref_lines[0].at == 4.5);
  CHECK(p.ref_lines[0].dash == Dash::kDotted);
  REQUIRE(p.x_limits);  // the drawn axes become fixed limits
  CHECK(p.x_limits->lo <= 0.0);
  CHECK(p.x_limits->hi >= 2.0);
}

TEST_CASE("figure JSON: a script's short figure takes the defaults and is drawn", "[plot]") {
  const auto j = nlohmann::json::parse(R"({"panels": [{"series": [{"x": [1, 2], "y": [0, 3], "width_px": 20}],
                                                       "y_axis": {"lo": 0, "hi": 4}}]})");
  const Figure figure = figure_from_json(j);
  CHECK(figure.panels()[0].series[0].dash == Dash::kSolid);
  CHECK(figure.panels()[0].y_limits->hi == 4.0);
  CHECK_FALSE(figure.panels()[0].x_limits);
  const std::string png =
      (std::filesystem::temp_directory_path() / ("mppi_figure_from_json_" + std::to_string(::getpid()) + ".png")).string();
  figure.write_png(png);
  CHECK(std::filesystem::file_size(png) > 1000);
  std::filesystem::remove(png);
}

TEST_CASE("figure JSON: bad values are refused, naming where", "[plot]") {
  auto error_of = [](const char* text) {
    try {
      figure_from_json(nlohmann::json::parse(text));
    } catch (const mppi::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(error_of(R"({"title": "x"})"), Contains("'panels' array"));
  CHECK_THAT(error_of(R"({"panels": [{"series": [{"x": [1]}]}]})"), Contains("panels[0].series[0] has no 'y'"));
  CHECK_THAT(error_of(R"({"panels": [{"series": [{"x": [1], "y": [1], "colour": "red"}]}]})"),
             Contains("not a colour"));
  CHECK_THAT(error_of(R"({"panels": [{"series": [{"x": [1], "y": [1], "dash": "wavy"}]}]})"), Contains("wavy"));
  CHECK(error_of(R"({"panels": [{"series": [{"x": [1, 2], "y": [1]}]}]})") != "no error");  // Figure::validate
}
