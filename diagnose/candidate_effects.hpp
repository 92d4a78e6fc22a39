#pragma once
// The candidate-effect library of the diagnosis: the effect table of the library
// (dynamics/effects.hpp), each effect with its parameters, their fit ranges, typical sizes,
// units and where it enters the physics.
#include "dynamics/effects.hpp"

namespace mppi::diagnose {

using ParamSpec = EffectParamSpec;
using mppi::EffectSpec;
using mppi::effect_spec;

// Every candidate, in a fixed order.
inline const std::vector<EffectSpec>& effect_library() { return effect_table(); }

}  // namespace mppi::diagnose
