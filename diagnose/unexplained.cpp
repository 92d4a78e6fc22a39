#include "diagnose/unexplained.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mppi::diagnose {

namespace {
std::string horizon_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g-s", s);
  return buf;
}

// Strongest (largest |z|) first, at most max_listed.
std::vector<Mismatch> strongest_first(std::vector<Mismatch> findings, int max_listed) {
  std::stable_sort(findings.begin(), findings.end(),
                   [](const Mismatch& a, const Mismatch& b) { return std::abs(a.z) > std::abs(b.z); });
  if (findings.size() > static_cast<std::size_t>(std::max(0, max_listed)))
    findings.resize(static_cast<std::size_t>(std::max(0, max_listed)));
  return findings;
}
}  // namespace

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
  return strongest_first(std::move(out), o.max_listed);
}

std::vector<Mismatch> long_horizon_unexplained(const std::vector<Mismatch>& nominal_long,
                                               const std::vector<Mismatch>& remaining_long, const UnexplainedOptions& o) {
  UnexplainedOptions all = o;
  all.max_listed = static_cast<int>(remaining_long.size());
  std::vector<Mismatch> out = unexplained_mismatch(nominal_long, remaining_long, all);
  for (Mismatch& m : out) m.where += " (" + horizon_text(o.long_horizon_s) + " predictions, all rows)";
  return out;
}

std::vector<Mismatch> unexplained_of_both(const std::vector<Mismatch>& nominal_short, const std::vector<Mismatch>& remaining_short,
                                          std::vector<Mismatch> long_look, const UnexplainedOptions& o) {
  UnexplainedOptions all = o;
  all.max_listed = static_cast<int>(remaining_short.size());
  std::vector<Mismatch> out = unexplained_mismatch(nominal_short, remaining_short, all);
  for (Mismatch& m : long_look) out.push_back(std::move(m));
  return strongest_first(std::move(out), o.max_listed);
}

void mark_partial_where_unexplained(const std::vector<Mismatch>& long_look, Selection* selection) {
  if (long_look.empty() || selection->selected.empty()) return;
  selection->partial.insert(selection->partial.end(), selection->selected.begin(), selection->selected.end());
  selection->selected.clear();
  std::string ids;
  for (const std::string& id : selection->partial) ids += (ids.empty() ? "" : ", ") + id;
  selection->verdict = "unexplained mismatch (" + long_look.front().channel + ", " + long_look.front().where +
                       "); partial correction: " + ids;
  selection->log.push_back("an unexplained mismatch remains (" + unexplained_summary({long_look.front()}) +
                           "): " + ids + " explain it in part and are not named");
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
