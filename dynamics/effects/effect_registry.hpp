#pragma once
// The effects declared in files of their own (dynamics/effects/), in one list. Each type E
// provides:
//   E::Params                     its parameters (EffectParams derives from every E::Params);
//   E::decl()                     its EffectDecl: id, units, ranges, hook, excitation, partner;
//   E::kStates                    the states it adds to WithEffects<Base>;
//   E::Term(params, chassis)      its physics for one model: active(), and for a chassis or force
//                                 hook add_body_accelerations<W>(lanes, its states, dt).
// The effect table (dynamics/effects.hpp) lists them after the built-in effects, and
// WithEffects<Base> (dynamics/with_effects.hpp) folds over the list. Adding an effect: its file
// here, one entry below, and its test.
#include <type_traits>

#include "base/type_list.hpp"
#include "dynamics/effects/tyre_relaxation.hpp"

namespace mppi::effects {

using DeclaredEffects = TypeList<TyreRelaxation>;

// Every declared effect's parameters in one struct (a base of EffectParams).
template <class List>
struct ParamsOfAll;
template <class... E>
struct ParamsOfAll<TypeList<E...>> : E::Params... {};

// The states all declared effects add, and where effect E's begin among them.
template <class List>
struct StatesOfAll;
template <class... E>
struct StatesOfAll<TypeList<E...>> {
  static constexpr int kCount = (0 + ... + E::kStates);
};
template <class E, class List>
struct StateOffset;
template <class E, class First, class... Rest>
struct StateOffset<E, TypeList<First, Rest...>> {
  static constexpr int kValue =
      std::is_same_v<E, First> ? 0 : First::kStates + StateOffset<E, TypeList<Rest...>>::kValue;
};
template <class E>
struct StateOffset<E, TypeList<>> {
  static constexpr int kValue = 0;
};

}  // namespace mppi::effects
