// mppi-plot: draws a figure described as JSON (the keys of plot/figure_json.hpp, read by
// plot/figure_from_json.hpp) to a PNG in the house style, for scripts that make figures
// without a plotting library of their own (scripts/robustness_benchmark.py).
#include <cstdio>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "base/error.hpp"
#include "plot/figure_from_json.hpp"

int main(int argc, char** argv) {
  const std::string usage = "usage: mppi-plot FIGURE.json OUT.png\n"
                            "Draws a figure described as JSON (plot/figure_from_json.hpp) to a PNG.\n";
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::fputs(usage.c_str(), stdout);
    return 0;
  }
  if (argc != 3) {
    std::fputs(usage.c_str(), stderr);
    return 2;
  }
  const std::string figure_json = argv[1], png = argv[2];
  try {
    std::ifstream in(figure_json);
    if (!in) throw mppi::Error(figure_json + ": cannot open");
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
      throw mppi::Error(figure_json + ": not JSON: " + e.what());
    }
    mppi::plot::figure_from_json(j).write_png(png);
    return 0;
  } catch (const mppi::Error& e) {
    std::fprintf(stderr, "mppi-plot: error: %s\n", e.what());
    return 2;
  }
}
