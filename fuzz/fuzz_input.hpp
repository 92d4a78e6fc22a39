#pragma once
// Helpers of the libFuzzer targets (fuzz/*.cpp): the input as text or as a file for the loaders
// that read a path, and the rule they all follow: a parser of outside data either returns a
// value or throws mppi::Error. Any other exception escapes the target and libFuzzer reports it
// as a crash (an unclear error is a bug too), as it does for sanitizer reports.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <unistd.h>

#include "base/error.hpp"

namespace mppi::fuzz {

inline std::string as_text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// A file of this process holding the input, for loaders that take a path; the name ends in
// `suffix` (some loaders look at it, e.g. OpenCV's image reader sniffs the content anyway).
inline std::string write_temp_file(const std::uint8_t* data, std::size_t size, const std::string& suffix) {
  const std::string path = "/tmp/mppi-fuzz-" + std::to_string(::getpid()) + suffix;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// Runs f(); an mppi::Error is the expected answer to bad input. Its message must say something.
template <class F>
void expect_value_or_error(F&& f) {
  try {
    f();
  } catch (const mppi::Error& e) {
    if (std::string(e.what()).empty()) __builtin_trap();
  }
}

}  // namespace mppi::fuzz
