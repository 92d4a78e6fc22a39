// The order in which the candidates that passed a selection round are tried: by how much they
// help on later data, with parsimony among the near-best and strong fit-part evidence deciding
// between near-equals.
#pragma once

#include <cstddef>
#include <vector>

namespace mppi::diagnose {

struct RankedCandidate {
  double improvement = 0;  // share by which it lowers the validation cost
  double bic = 0;          // BIC change on the fit part (lower: stronger evidence)
  std::size_t params = 0;  // parameters the data use
};

// Indices into `passed`, best first. Ranked by improvement; those within `parsimony_share` of the
// best come first, fewest parameters first, then by improvement. A near-best candidate whose BIC
// is at least `strong_bic_evidence` below the leader's takes the lead when it has as many
// parameters, or more parameters and a larger improvement too (its BIC already charges for them).
std::vector<std::size_t> rank_passing_candidates(const std::vector<RankedCandidate>& passed, double parsimony_share,
                                                 double strong_bic_evidence);

}  // namespace mppi::diagnose
