#pragma once
// The message of the mppi::Error that f throws, or a marker when it throws none.
#include <functional>
#include <string>

#include "base/error.hpp"

namespace mppi::test {
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const mppi::Error& e) {
    return e.what();
  }
  return "(no mppi::Error thrown)";
}
}  // namespace mppi::test
