#pragma once
// A compile-time list of types (the registered models, costs) and name lookup over it.
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

namespace mppi {

template <class... T>
struct TypeList {};

template <class List>
struct FrontOfImpl;
template <class T, class... Rest>
struct FrontOfImpl<TypeList<T, Rest...>> {
  using type = T;
};
template <class List>
using FrontOf = typename FrontOfImpl<List>::type;

// f.template operator()<T>() for each T, in order.
template <class... T, class F>
void for_each_type(TypeList<T...>, F&& f) {
  (f.template operator()<T>(), ...);
}

// f.template operator()<T>() for the T whose T::kName equals `name`; false if none.
// For a visitor that returns a value, `result` receives it.
template <class... T, class F, class R>
bool visit_by_name(TypeList<T...>, std::string_view name, F&& f, std::optional<R>& result) {
  return ((name == std::string_view(T::kName) ? (result.emplace(f.template operator()<T>()), true) : false) || ...);
}
template <class... T, class F>
bool visit_by_name(TypeList<T...>, std::string_view name, F&& f) {
  return ((name == std::string_view(T::kName) ? (f.template operator()<T>(), true) : false) || ...);
}

// "a, b, c": the kName of each T.
template <class... T>
std::string names_of(TypeList<T...>) {
  std::string out;
  ((out += (out.empty() ? "" : ", ") + std::string(T::kName)), ...);
  return out;
}

}  // namespace mppi
