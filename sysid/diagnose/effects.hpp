#pragma once
// The candidate-effect library: each effect is a named physical term of CorrectedSingleTrack
// (dynamics/corrected_single_track.hpp) with its physical parameters, their admissible range,
// a typical size (finite-difference step, search grid) and unit.
#include <string>
#include <vector>

#include "dynamics/corrected_single_track.hpp"

namespace mppi::diagnose {

struct ParamSpec {
  const char* name;             // key in the corrected-model file (EffectParams field)
  double EffectParams::*member;
  double lo, hi;                // admissible range (fits are projected onto it)
  double scale;                 // typical size: finite-difference step = 0.01 scale
  const char* unit;
};

struct EffectSpec {
  std::string id;               // effect id, e.g. "steer_delay"
  std::string description;      // one line, physical meaning
  std::vector<ParamSpec> params;
  std::vector<double> grid;     // start values searched for params[0] (empty: its default)
  bool time_grid = false;       // params[0] is a time searched over the data (not LM-fitted)
};

// Every candidate, in a fixed order.
const std::vector<EffectSpec>& effect_library();
// The spec of an id; throws mppi::Error listing the ids if unknown.
const EffectSpec& effect_spec(const std::string& id);

}  // namespace mppi::diagnose
