#pragma once
// A self-contained HTML report: Markdown text (GitHub flavour, rendered by cmark-gfm) whose
// images of figures are replaced by the same figures drawn interactively on canvases (data
// embedded as JSON in the page, a small script draws them and shows the values under the
// pointer). Nothing is fetched over the network.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace mppi::plot {

struct HtmlFigure {
  std::string image_file;        // the image the Markdown names, e.g. "overlay.png"
  nlohmann::ordered_json figure;  // figure_to_json(...)
};

// The id of the <script type="application/json"> element that holds the figures (an array,
// in the order given).
inline constexpr const char* kHtmlFiguresElementId = "mppi-figures";

// Throws mppi::Error if the file cannot be written.
void write_html_report(const std::string& path, const std::string& title, const std::string& markdown,
                       const std::vector<HtmlFigure>& figures);

// The page as a string (what write_html_report writes).
std::string html_report(const std::string& title, const std::string& markdown, const std::vector<HtmlFigure>& figures);

}  // namespace mppi::plot
