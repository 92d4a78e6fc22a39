#include "plot/html_report.hpp"

#include <cmark-gfm-core-extensions.h>
#include <cmark-gfm.h>

#include <cstdlib>
#include <fstream>
#include <memory>
#include <mutex>

#include "base/error.hpp"

namespace mppi::plot {

extern const char* const kChartsJs;

namespace {

const char* const kStyle = R"css(
body { font-family: "DejaVu Sans", Verdana, sans-serif; color: #141414; margin: 0; background: #fff; }
main { max-width: 1280px; margin: 0 auto; padding: 8px 24px 48px; }
table { border-collapse: collapse; margin: 8px 0 16px; font-size: 13px; }
th, td { border: 1px solid #d0d0d0; padding: 3px 8px; text-align: left; }
th { background: #f2f2f2; }
pre { background: #f6f6f6; padding: 8px; overflow-x: auto; font-size: 12px; }
code { font-family: "DejaVu Sans Mono", monospace; }
.mppi-figure { margin: 12px 0 24px; }
.mppi-figure-title { font-size: 17px; text-align: center; margin: 4px 0; }
.mppi-panels { display: grid; gap: 0; }
.mppi-panels canvas { display: block; }
.mppi-tip { position: fixed; pointer-events: none; background: rgba(255,255,255,0.95); border: 1px solid #999;
            padding: 3px 6px; font-size: 12px; display: none; white-space: pre; z-index: 10; }
)css";

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '&': o += "&amp;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

// Markdown (GitHub flavour: tables, strikethrough, autolinks) to HTML.
std::string markdown_to_html(const std::string& markdown) {
  static std::once_flag registered;
  std::call_once(registered, [] { cmark_gfm_core_extensions_ensure_registered(); });
  std::unique_ptr<cmark_parser, decltype(&cmark_parser_free)> parser(cmark_parser_new(CMARK_OPT_DEFAULT),
                                                                      &cmark_parser_free);
  for (const char* name : {"table", "strikethrough", "autolink"})
    if (cmark_syntax_extension* ext = cmark_find_syntax_extension(name))
      cmark_parser_attach_syntax_extension(parser.get(), ext);
  cmark_parser_feed(parser.get(), markdown.data(), markdown.size());
  std::unique_ptr<cmark_node, decltype(&cmark_node_free)> doc(cmark_parser_finish(parser.get()), &cmark_node_free);
  char* html = cmark_render_html(doc.get(), CMARK_OPT_DEFAULT, cmark_parser_get_syntax_extensions(parser.get()));
  std::string out(html ? html : "");
  std::free(html);
  return out;
}

// JSON inside <script>: "</" would end the element; "<\/" is the same JSON string.
std::string script_safe(std::string json) {
  for (std::size_t i = json.find("</"); i != std::string::npos; i = json.find("</", i + 3)) json.replace(i, 2, "<\\/");
  return json;
}

}  // namespace

std::string html_report(const std::string& title, const std::string& markdown, const std::vector<HtmlFigure>& figures) {
  std::string body = markdown_to_html(markdown);
  // Each <img src="FILE" ...> of a figure becomes the place its interactive copy is drawn.
  std::vector<bool> placed(figures.size(), false);
  for (std::size_t f = 0; f < figures.size(); ++f) {
    const std::string src = "src=\"" + figures[f].image_file + "\"";
    const std::size_t at = body.find(src);
    if (at == std::string::npos) continue;
    const std::size_t open = body.rfind("<img", at), close = body.find('>', at);
    if (open == std::string::npos || close == std::string::npos) continue;
    body.replace(open, close + 1 - open, "<div class=\"mppi-figure\" data-figure=\"" + std::to_string(f) + "\"></div>");
    placed[f] = true;
  }
  for (std::size_t f = 0; f < figures.size(); ++f)
    if (!placed[f]) body += "<div class=\"mppi-figure\" data-figure=\"" + std::to_string(f) + "\"></div>\n";
  nlohmann::ordered_json all = nlohmann::ordered_json::array();
  for (const HtmlFigure& f : figures) all.push_back(f.figure);
  std::string page;
  page += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" + html_escape(title) +
          "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n<main>\n" + body + "</main>\n";
  page += "<div class=\"mppi-tip\" id=\"mppi-tip\"></div>\n";
  page += "<script type=\"application/json\" id=\"" + std::string(kHtmlFiguresElementId) + "\">" +
          script_safe(all.dump()) + "</script>\n";
  page += "<script>\n" + std::string(kChartsJs) + "</script>\n</body>\n</html>\n";
  return page;
}

void write_html_report(const std::string& path, const std::string& title, const std::string& markdown,
                       const std::vector<HtmlFigure>& figures) {
  const std::string page = html_report(title, markdown, figures);
  std::ofstream out(path, std::ios::binary);
  if (!out) throw Error(path + ": cannot write the HTML report");
  out << page;
  if (!out.flush()) throw Error(path + ": cannot write the HTML report");
}

}  // namespace mppi::plot
