#include "diagnose/unexplained.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mppi::diagnose {

std::vector<Mismatch> unexplained_mismatch(const std::vector<Mismatch>& nominal, const std::vector<Mismatch>& remaining,
                                           const UnexplainedOptions& o) {
  auto largest_nominal = [&](const std::string& channel) {
    double largest = 0;
    for (const Mismatch& m : nominal)
      if (m.channel == channel) largest = std::max(largest, std::abs(m.magnitude));
    return largest;
  };
  std::vector<Mismatch> out;
  for (const Mismatch& m : remaining) {
    if (!(std::abs(m.z) >= o.min_z)) continue;
    // A channel the nominal model got right that the correction got wrong counts whatever its size.
    if (std::abs(m.magnitude) < o.min_share_of_nominal * largest_nominal(m.channel)) continue;
    out.push_back(m);
  }
  std::stable_sort(out.begin(), out.end(), [](const Mismatch& a, const Mismatch& b) { return std::abs(a.z) > std::abs(b.z); });
  if (out.size() > static_cast<std::size_t>(std::max(0, o.max_listed))) out.resize(static_cast<std::size_t>(std::max(0, o.max_listed)));
  return out;
}

std::string unexplained_summary(const std::vector<Mismatch>& unexplained) {
  if (unexplained.empty()) return "none";
  std::string out;
  for (const Mismatch& m : unexplained) {
    char line[256];
    std::snprintf(line, sizeof line, "%s%s, %s: %.3g %s (z %.1f)", out.empty() ? "" : "; ", m.channel.c_str(),
                  m.where.c_str(), m.magnitude, m.unit.c_str(), m.z);
    out += line;
  }
  return out;
}

}  // namespace mppi::diagnose
