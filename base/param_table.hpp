#pragma once
// A component's parameters as one table: YAML key, where the value lives, unit, valid range,
// and a doc line. The table is declared once, next to the component (its descriptor), and the
// YAML loader and writer (base/param_yaml.hpp), the range part of is_valid(), the estimators'
// named-parameter vectors and the --help text all come from it. Defaults are the values of a
// default-constructed parameter struct.
//
// A table is made from an instance: `fields(p)` returns entries pointing into `p`, so nested
// structs (the tyre inside the single-track parameters, the single-track parameters inside the
// double-track ones) compose by calling the inner table on the inner member. Keys of a nested
// map are written "outer.inner" (e.g. "tyre.B"), which the YAML reader maps to `tyre: {B: ..}`.
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace mppi {

// Which ends of [lo, hi] a value may take.
enum class Bounds { kClosed, kOpenLow, kOpenHigh, kOpen };

struct ParamField {
  const char* key;     // YAML key; "outer.inner" for a key inside a nested map
  double* value;       // the value, inside the instance the table was made from (or value_f)
  const char* unit;    // SI unit in words ("kg", "m/s", "-")
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  Bounds bounds = Bounds::kClosed;
  const char* doc = "";
  float* value_f = nullptr;  // a float parameter (value is then null)

  double get() const { return value_f ? static_cast<double>(*value_f) : *value; }
  void set(double v) const {
    if (value_f) *value_f = static_cast<float>(v);
    else *value = v;
  }
};

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Range helpers for table entries: {key, &p.x, "kg", positive(), "doc"} reads as it means.
struct Range {
  double lo, hi;
  Bounds bounds;
};
inline constexpr Range positive() { return {0.0, kInf, Bounds::kOpen}; }
inline constexpr Range non_negative() { return {0.0, kInf, Bounds::kOpenHigh}; }
inline constexpr Range any_finite() { return {-kInf, kInf, Bounds::kOpen}; }
inline constexpr Range open(double lo, double hi) { return {lo, hi, Bounds::kOpen}; }
inline constexpr Range closed(double lo, double hi) { return {lo, hi, Bounds::kClosed}; }
inline constexpr Range open_low(double lo, double hi) { return {lo, hi, Bounds::kOpenLow}; }
// > 0, and +inf allowed (e.g. a limit that +inf turns off).
inline constexpr Range positive_or_inf() { return {0.0, kInf, Bounds::kOpenLow}; }
// Any value but NaN, infinities included.
inline constexpr Range not_nan() { return {-kInf, kInf, Bounds::kClosed}; }

inline ParamField param(const char* key, double* value, const char* unit, Range range, const char* doc) {
  return ParamField{key, value, unit, range.lo, range.hi, range.bounds, doc};
}
inline ParamField param(const char* key, float* value, const char* unit, Range range, const char* doc) {
  return ParamField{key, nullptr, unit, range.lo, range.hi, range.bounds, doc, value};
}

// "must be > 0", "must be in [0, 1]", ...: the range as the error message states it.
inline std::string range_text(const ParamField& f) {
  const bool lo_open = f.bounds == Bounds::kOpen || f.bounds == Bounds::kOpenLow;
  const bool hi_open = f.bounds == Bounds::kOpen || f.bounds == Bounds::kOpenHigh;
  std::ostringstream s;
  s.precision(6);
  if (std::isinf(f.hi) && std::isinf(f.lo)) return f.bounds == Bounds::kClosed ? "not NaN" : "finite";
  if (std::isinf(f.hi)) {
    s << (lo_open ? "> " : ">= ") << f.lo << (hi_open ? "" : " (+inf allowed)");
    return s.str();
  }
  if (std::isinf(f.lo)) {
    s << (hi_open ? "< " : "<= ") << f.hi;
    return s.str();
  }
  s << "in " << (lo_open ? "(" : "[") << f.lo << ", " << f.hi << (hi_open ? ")" : "]");
  return s.str();
}

// True if the value is inside the field's range: never NaN; an infinity only where the range
// is closed at that infinite end (positive_or_inf(), not_nan()).
inline bool in_range(const ParamField& f) {
  const double v = f.get();
  const bool lo_open = f.bounds == Bounds::kOpen || f.bounds == Bounds::kOpenLow;
  const bool hi_open = f.bounds == Bounds::kOpen || f.bounds == Bounds::kOpenHigh;
  if (std::isnan(v)) return false;
  if (std::isinf(v) && (v > 0 ? hi_open || !std::isinf(f.hi) : lo_open || !std::isinf(f.lo))) return false;
  if (lo_open ? !(v > f.lo) : !(v >= f.lo)) return false;
  if (hi_open ? !(v < f.hi) : !(v <= f.hi)) return false;
  return true;
}

// The first field out of range, as "<key> must be <range>"; empty if all are in range.
inline std::string first_range_error(const std::vector<ParamField>& fields) {
  for (const ParamField& f : fields)
    if (!in_range(f)) return std::string(f.key) + " must be " + range_text(f);
  return {};
}

// One line per field: key, default, unit, range, doc (for --help and docs).
inline std::string param_help(const std::vector<ParamField>& fields) {
  std::ostringstream s;
  s.precision(6);
  for (const ParamField& f : fields)
    s << "  " << f.key << " = " << f.get() << " [" << f.unit << "], " << range_text(f) << ": " << f.doc
      << "\n";
  return s.str();
}

}  // namespace mppi
