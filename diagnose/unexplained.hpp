#pragma once
// "Unexplained mismatch": what the corrected model still gets wrong, stated as an answer. After
// the selection, the corrected model's residuals are located on the held-out part (locate.hpp:
// per channel, by regime, in time and by place on the track). A finding there is unexplained
// where the data resolve it clearly and it is not a small remainder of a mismatch the correction
// took away: the library holds no term that explains it (or none was among the candidates), and
// the report says where it sits and how large it is instead of leaving it to the nearest name.
// Where a mismatch stays unexplained, the effects the selection chose explain it only in part:
// they are reported as a partial correction (they improve the prediction and are written to the
// model file), not as the physics that was missing.
#include <string>
#include <vector>

#include "diagnose/fit.hpp"
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
  // A second look at a longer horizon, over all rows (fitted and held out): a term that only
  // mimics the missing one takes most of the short predictions' error away but leaves a drift
  // that builds over a second; the longer horizon shows the drift with less of the sensor noise,
  // and all rows resolve it. The correction has a few parameters, so the rows it was fitted on
  // hide little of what its form cannot follow. 0 = no second look.
  double long_horizon_s = 1.0;
};

// The remaining findings (the corrected model's, held out) that are unexplained, strongest first.
// `nominal`: the nominal model's findings (their sizes per channel are the reference).
std::vector<Mismatch> unexplained_mismatch(const std::vector<Mismatch>& nominal, const std::vector<Mismatch>& remaining,
                                           const UnexplainedOptions& o = {});

// The long look's unexplained findings (its nominal findings at the same horizon and rows as the
// reference), each marked "(<horizon>-s predictions, all rows)".
std::vector<Mismatch> long_horizon_unexplained(const std::vector<Mismatch>& nominal_long,
                                               const std::vector<Mismatch>& remaining_long, const UnexplainedOptions& o = {});

// The two looks joined, strongest first, at most o.max_listed: the short look's findings judged
// against the nominal model's located mismatch (training rows, as the diagnosis locates it), and
// the long look's unexplained findings (`long_look`: long_horizon_unexplained).
std::vector<Mismatch> unexplained_of_both(const std::vector<Mismatch>& nominal_short, const std::vector<Mismatch>& remaining_short,
                                          std::vector<Mismatch> long_look, const UnexplainedOptions& o = {});

// Where the long look leaves an unexplained mismatch (`long_look`: long_horizon_unexplained), the
// selection's named effects become its partial correction (Selection::partial) and the verdict
// says so; else the selection is left as it is.
// - The short look's findings do not demote: on the held-out part at 0.2 s a right correction can
//   still leave a place or a moment it does not reach (the steering's end stop, a window of time),
//   whereas what a mimic leaves is a drift that builds over the longer horizon.
// - A long-look finding in a channel the nominal model got right demotes too: a term that mimics
//   the missing one in one regime distorts another (a weaker motor for a heavier car accelerates
//   the car wrongly where the nominal model was right on average), and a term the data do not
//   hold leaves its mark where it acts. Either way the names are not the whole story.
void mark_partial_where_unexplained(const std::vector<Mismatch>& long_look, Selection* selection);

// One line: "vx, overall: -0.189 m/s^2 (z -6.7); ..." ("none" for an empty list).
std::string unexplained_summary(const std::vector<Mismatch>& unexplained);

}  // namespace mppi::diagnose
