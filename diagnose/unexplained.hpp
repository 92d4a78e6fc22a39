#pragma once
// "Unexplained mismatch": what the corrected model still gets wrong, stated as an answer. After
// the selection, the corrected model's residuals are located on the held-out part (locate.hpp:
// per channel, by regime, in time and by place on the track). A finding there is unexplained
// where the data resolve it clearly and it is not a small remainder of a mismatch the correction
// took away: the library holds no term that explains it (or none was among the candidates), and
// the report says where it sits and how large it is instead of leaving it to the nearest name.
#include <string>
#include <vector>

#include "diagnose/locate.hpp"

namespace mppi::diagnose {

struct UnexplainedOptions {
  // |z| of a remaining finding: locate lists findings from z = 4; at 5 a mean that large arises
  // by chance about once in 3.5 million independent samples, more than any recording holds.
  double min_z = 5.0;
  // Its size against the largest finding of its channel before the correction: a correction that
  // took a mismatch mostly away leaves a remainder a long recording still resolves (a fitted value
  // a little off); a fifth of the original is more than that.
  double min_share_of_nominal = 0.2;
  // At most this many are reported (strongest first); the rest are in the remaining list.
  int max_listed = 3;
};

// The remaining findings (the corrected model's, held out) that are unexplained, strongest first.
// `nominal`: the nominal model's findings (their sizes per channel are the reference).
std::vector<Mismatch> unexplained_mismatch(const std::vector<Mismatch>& nominal, const std::vector<Mismatch>& remaining,
                                           const UnexplainedOptions& o = {});

// One line: "vx, overall: -0.189 m/s^2 (z -6.7); ..." ("none" for an empty list).
std::string unexplained_summary(const std::vector<Mismatch>& unexplained);

}  // namespace mppi::diagnose
