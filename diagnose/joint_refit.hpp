#pragma once
// The final fit of the effects a selection names: all of them together, on all training data,
// with each parameter checked against the end of its search range.
#include <string>
#include <utility>
#include <vector>

#include "diagnose/fit.hpp"

namespace mppi::diagnose {

struct JointRefit {
  std::vector<std::string> kept;             // the effects identified together, in the given order
  EffectParams effects;                      // their joint fit (everything else at its default)
  std::vector<ParamEstimate> params;         // the fitted parameters (not the held ones, not change times)
  std::vector<std::string> held;             // "effect: parameter" held at its nominal value
  std::vector<std::pair<std::string, std::string>> not_identified;  // effect id, why
  std::vector<std::string> log;              // one line per decision
};

// One round of a greedy selection: the effect ids chosen by then and their fitted values.
struct SelectionRound {
  std::vector<std::string> chosen;
  EffectParams effects;
};

// Where the joint refit of `named` starts. Later rounds of a selection refit the earlier effects
// together with effects that end up not named (unstable, another form of a named one), which can
// move them to another local optimum. So the refit starts from the last round whose chosen
// effects are all named (its values for those effects; every other parameter from `fallback`),
// or from `fallback` itself when every effect of the selection's final state (`final_chosen`) is
// named or no round qualifies.
EffectParams joint_refit_start(const std::vector<SelectionRound>& rounds, const std::vector<std::string>& final_chosen,
                               const std::vector<std::string>& named, const EffectParams& fallback);

// Fits the parameters of `named` together on `all`, from `start`. A parameter that ends at the end
// of its search range (range_limit_param) is held at its nominal value and the effect's other
// parameters refitted: the nested, simpler form (a rolling resistance without its viscous part).
// An effect with nothing else left to fit is not identified and is dropped. Each pass finalises,
// drops an effect or holds a parameter, so the loop ends. A change time (DataGrid::kTime) was
// searched over the data and stays where `start` has it.
JointRefit refit_named_jointly(const FitProblem& all, const std::vector<std::string>& named, EffectParams start,
                               double range_limit_margin);

}  // namespace mppi::diagnose
