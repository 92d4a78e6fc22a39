#include "diagnose/substitutes.hpp"

#include <algorithm>

namespace mppi::diagnose {
namespace {

bool contains(const std::vector<std::string>& v, const std::string& x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

}  // namespace

std::vector<SubstitutePair> find_substitutes(const std::vector<std::string>& named,
                                             const std::vector<std::string>& chosen_on_all,
                                             const std::vector<std::vector<std::string>>& resamples,
                                             const std::function<std::string(const std::string&)>& dynamics_of) {
  std::vector<SubstitutePair> out;
  for (const std::string& i : named) {
    const std::string family = dynamics_of(i);
    // Rivals in the order the resamples took them.
    std::vector<std::string> rivals;
    for (const auto& took : resamples)
      for (const std::string& j : took)
        if (j != i && !contains(chosen_on_all, j) && !contains(rivals, j) &&
            (family.empty() || dynamics_of(j) != family))
          rivals.push_back(j);
    for (const std::string& j : rivals) {
      bool together = false, in_place = false;
      for (const auto& took : resamples) {
        const bool has_i = contains(took, i), has_j = contains(took, j);
        together = together || (has_i && has_j);
        in_place = in_place || (has_j && !has_i);
      }
      if (in_place && !together) {
        out.push_back({i, j});
        break;
      }
    }
  }
  return out;
}

void mark_partial_where_substituted(const std::vector<SubstitutePair>& substitutes, Selection* selection) {
  std::vector<std::string> kept, moved;
  for (const std::string& id : selection->selected) {
    const bool substituted = std::any_of(substitutes.begin(), substitutes.end(),
                                         [&](const SubstitutePair& p) { return p.named == id; });
    (substituted ? moved : kept).push_back(id);
  }
  if (moved.empty()) return;
  std::string pairs, ids;
  for (const SubstitutePair& p : substitutes)
    if (contains(moved, p.named)) pairs += (pairs.empty() ? "" : "; ") + p.named + " or " + p.substitute;
  for (const std::string& id : moved) ids += (ids.empty() ? "" : ", ") + id;
  selection->selected = kept;
  selection->partial.insert(selection->partial.end(), moved.begin(), moved.end());
  selection->ambiguous = pairs;
  for (CandidateReport& c : selection->candidates)
    if (contains(moved, c.id)) c.selected = false;
  std::string named;
  for (const std::string& id : kept) named += (named.empty() ? "" : ", ") + id;
  selection->verdict = kept.empty() ? "ambiguous (" + pairs + "); partial correction: " + ids
                                    : "named: " + named + "; ambiguous (" + pairs + "): " + ids + " a partial correction";
  selection->log.push_back("substitutes in the resamples (" + pairs + "): " + ids + " a partial correction, not named");
}

}  // namespace mppi::diagnose
