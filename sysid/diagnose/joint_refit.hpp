#pragma once
// The final fit of the effects a selection names: all of them together, on all training data,
// with each parameter checked against the end of its search range.
#include <string>
#include <utility>
#include <vector>

#include "sysid/diagnose/fit.hpp"

namespace mppi::diagnose {

struct JointRefit {
  std::vector<std::string> kept;             // the effects identified together, in the given order
  EffectParams effects;                      // their joint fit (everything else at its default)
  std::vector<ParamEstimate> params;         // the fitted parameters (not the held ones, not change times)
  std::vector<std::string> held;             // "effect: parameter" held at its nominal value
  std::vector<std::pair<std::string, std::string>> not_identified;  // effect id, why
  std::vector<std::string> log;              // one line per decision
};

// Fits the parameters of `named` together on `all`, from `start`. A parameter that ends at the end
// of its search range (range_limit_param) is held at its nominal value and the effect's other
// parameters refitted: the nested, simpler form (a rolling resistance without its viscous part).
// An effect with nothing else left to fit is not identified and is dropped. Each pass finalises,
// drops an effect or holds a parameter, so the loop ends. A change time (DataGrid::kTime) was
// searched over the data and stays where `start` has it.
JointRefit refit_named_jointly(const FitProblem& all, const std::vector<std::string>& named, EffectParams start,
                               double range_limit_margin);

}  // namespace mppi::diagnose
