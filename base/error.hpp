#pragma once
// mppi::Error: the one exception type thrown at API boundaries (bad files, bad options).
// Hot loops never throw; they report through return values and summaries instead.
#include <stdexcept>
#include <string>

namespace mppi {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace mppi
