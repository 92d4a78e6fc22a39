#include "diagnose/ranking.hpp"

#include <algorithm>
#include <numeric>

namespace mppi::diagnose {

std::vector<std::size_t> rank_passing_candidates(const std::vector<RankedCandidate>& passed, double parsimony_share,
                                                 double strong_bic_evidence) {
  std::vector<std::size_t> order(passed.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  if (order.empty()) return order;
  auto at = [&](std::size_t i) -> const RankedCandidate& { return passed[i]; };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return at(a).improvement > at(b).improvement; });
  // Among those within parsimony_share of the best, the one with the fewest parameters the data
  // use comes first (c v^2 over F0 + b v on a speed range; F0 alone ties with c v^2 and the
  // better one wins).
  const double near_best = parsimony_share * at(order.front()).improvement;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const bool na = at(a).improvement >= near_best, nb = at(b).improvement >= near_best;
    if (na != nb) return na;
    return na && at(a).params < at(b).params;
  });
  // Between near-best candidates of as many parameters, the validation difference is within its
  // noise; strong evidence on the fit part (more data: a BIC lower by >= 6) decides. A near-best
  // candidate with more parameters takes the lead the same way when it also does better on the
  // later data: its BIC has already paid for the parameters it adds.
  const RankedCandidate& front = at(order.front());
  auto stronger = order.begin();
  for (auto it = order.begin(); it != order.end(); ++it) {
    const RankedCandidate& c = at(*it);
    if (c.improvement < near_best) continue;
    const bool as_many = c.params == front.params;
    const bool more_and_better = c.params > front.params && c.improvement > front.improvement;
    if ((as_many || more_and_better) && c.bic < at(*stronger).bic) stronger = it;
  }
  if (at(*stronger).bic <= front.bic - strong_bic_evidence) std::rotate(order.begin(), stronger, stronger + 1);
  return order;
}

}  // namespace mppi::diagnose
