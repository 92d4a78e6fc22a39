#pragma once
// Pieces every vehicle model spec is built from: the estimated parameters checked and listed,
// the sample interval split into integration substeps, and recording values with a fallback.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "sysid/prepared_recording.hpp"
#include "sysid/model_param_fields.hpp"
#include "sysid/vehicle_model_spec.hpp"

namespace mppi::sysid::detail {

inline std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// Fills spec.estimated, nominal and log_scale from `estimated`, the values read from `base` through
// `field`; throws mppi::Error for an unknown or repeated name, or a log-scale one that is not > 0.
template <class P, class FieldFn>
void prepare(VehicleModelSpec& spec, const P& base, const std::vector<std::string>& estimated,
             const std::vector<std::string>& known, FieldFn field) {
  P copy = base;
  for (const auto& n : estimated) {
    const double* f = field(copy, n);
    if (!f) throw Error("unknown parameter '" + n + "' for the " + spec.kind + " model (known: " + join(known) + ")");
    if (std::count(estimated.begin(), estimated.end(), n) > 1) throw Error("parameter '" + n + "' given twice");
    spec.estimated.push_back(n);
    spec.nominal.push_back(*f);
    const bool lin = is_linear_param(n);
    if (!lin && !(*f > 0)) throw Error("parameter '" + n + "' must be > 0 to be estimated (log scale)");
    spec.log_scale.push_back(!lin);
  }
}

// Integrates `dt` in equal substeps of at most max_sub.
template <class StepFn>
void substep(double dt, double max_sub, StepFn&& fn) {
  const int n = std::max(1, static_cast<int>(std::ceil(dt / max_sub - 1e-9)));
  for (int i = 0; i < n; ++i) fn(dt / n);
}

inline double value_or(const PreparedRecording& rec, const char* col, std::size_t row, double fallback) {
  const std::vector<double>* c = rec.find_column(col);
  if (!c) return fallback;
  const double v = (*c)[row];
  return std::isfinite(v) ? v : fallback;
}

}  // namespace mppi::sysid::detail
