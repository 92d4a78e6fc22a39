#pragma once
// Substitutes among the stability resamples (selection stage "stability"): a named effect and an
// effect that the selection on all the data did not choose, which never appear in one resample,
// where some resample took the other in the named one's place. Two physical explanations then
// fit one mismatch about as well, and which one holds is a coin toss over the resamples: a term
// that mimics a missing one (a throttle gain or a weaker motor where the car carries a payload)
// looks like this, while an effect the data pin down is chosen in every resample or is left out
// without a rival taking its place. Other forms of one actuator's dynamics (a delay and a lag)
// are not substitutes: they are one physical explanation in two forms.
#include <functional>
#include <string>
#include <vector>

#include "diagnose/fit.hpp"

namespace mppi::diagnose {

struct SubstitutePair {
  std::string named, substitute;
};

// named: the effects the selection names; chosen_on_all: those chosen on all the data (joint
// candidates as their members); resamples: the library effects each resample chose;
// dynamics_of: an effect's actuator ("" for none). At most one substitute per named effect: the
// first found, in the resamples' order.
std::vector<SubstitutePair> find_substitutes(const std::vector<std::string>& named,
                                             const std::vector<std::string>& chosen_on_all,
                                             const std::vector<std::vector<std::string>>& resamples,
                                             const std::function<std::string(const std::string&)>& dynamics_of);

// A named effect with a substitute explains the mismatch, but the data do not say which physics
// it is: it becomes part of the partial correction (Selection::partial: in the model file, not
// named), Selection::ambiguous lists the pairs, and the verdict reads "named: <the others>;
// ambiguous (<named> or <substitute>; ...): <ids> a partial correction" (or, with nothing left
// named, "ambiguous (...); partial correction: <ids>"). Effects without a substitute stay named.
void mark_partial_where_substituted(const std::vector<SubstitutePair>& substitutes, Selection* selection);

}  // namespace mppi::diagnose
