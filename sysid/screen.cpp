#include "sysid/screen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace mppi::sysid {

namespace {

enum class Kind { kPosition, kAngle, kVelocity, kYawRate, kCommand, kTime };

Kind kind_of(const std::string& name) {
  if (name == "x" || name == "y") return Kind::kPosition;
  if (name == "yaw" || name == "roll") return Kind::kAngle;
  if (name == "vx" || name == "vy") return Kind::kVelocity;
  if (name == "yaw_rate") return Kind::kYawRate;
  if (name == "t") return Kind::kTime;
  return Kind::kCommand;
}

// Difference of consecutive samples; angles wrap to (-pi, pi] (a yaw that wraps is no jump).
double difference(Kind kind, double a, double b) {
  double d = b - a;
  if (kind == Kind::kAngle) d = std::remainder(d, 2.0 * std::numbers::pi);
  return d;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

double bound_of(Kind kind, const ScreenOptions& o) {
  switch (kind) {
    case Kind::kPosition: return o.max_position_m;
    case Kind::kVelocity: return o.max_speed_mps;
    case Kind::kYawRate: return o.max_yaw_rate_radps;
    case Kind::kCommand: return o.max_command;
    case Kind::kAngle:
    case Kind::kTime: return std::numeric_limits<double>::infinity();
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

std::vector<ScreenFlag> screen_columns(const std::vector<double>& t, const std::vector<ScreenColumn>& columns,
                                       const ScreenOptions& o) {
  std::vector<ScreenFlag> flags;
  const std::size_t n = t.size();
  std::vector<char> flagged;
  auto flag = [&](std::size_t k, const std::string& column, double value, const char* kind) {
    flagged[k] = 1;
    flags.push_back({"", k, std::isfinite(t[k]) ? t[k] : std::numeric_limits<double>::quiet_NaN(), column, value, kind});
  };
  // Position jumps (a respawn): a velocity step there is not a fault.
  std::vector<char> position_jump(n, 0);
  const std::vector<double>* x = nullptr;
  const std::vector<double>* y = nullptr;
  for (const ScreenColumn& c : columns) {
    if (c.name == "x") x = c.values;
    if (c.name == "y") y = c.values;
  }
  for (std::size_t k = 1; x && y && k < n; ++k) {
    const double dt = t[k] - t[k - 1];
    const double step = std::hypot((*x)[k] - (*x)[k - 1], (*y)[k] - (*y)[k - 1]);
    position_jump[k] = step > o.max_speed_mps * std::abs(dt) + 0.2;
  }

  for (const ScreenColumn& c : columns) {
    const std::vector<double>& v = *c.values;
    const Kind kind = kind_of(c.name);
    flagged.assign(n, 0);
    const bool has_finite = std::any_of(v.begin(), v.end(), [](double a) { return std::isfinite(a); });
    if (!has_finite) continue;  // the recording lacks this channel
    const double bound = bound_of(kind, o);
    for (std::size_t k = 0; k < n; ++k) {
      if (!std::isfinite(v[k])) flag(k, c.name, v[k], "non-finite");
      else if (std::abs(v[k]) > bound) flag(k, c.name, v[k], "impossible");
    }
    if (kind == Kind::kCommand || kind == Kind::kTime) continue;  // held commands step by design
    // Robust scale of the first differences between rows not flagged so far.
    std::vector<double> diffs;
    diffs.reserve(n);
    for (std::size_t k = 1; k < n; ++k)
      if (!flagged[k] && !flagged[k - 1]) diffs.push_back(difference(kind, v[k - 1], v[k]));
    if (diffs.size() < 8) continue;
    const double med = median(diffs);
    for (double& d : diffs) d = std::abs(d - med);
    const double sigma = std::max(1.4826 * median(diffs), 1e-9);
    const double limit = o.robust_z * sigma;
    for (std::size_t k = 1; k + 1 < n; ++k) {
      if (flagged[k - 1] || flagged[k] || flagged[k + 1]) continue;
      const double in = difference(kind, v[k - 1], v[k]) - med;
      const double out = difference(kind, v[k], v[k + 1]) - med;
      if (std::abs(in) > limit && std::abs(out) > limit && (in > 0) != (out > 0)) {
        flag(k, c.name, v[k], "spike");
        continue;
      }
      if ((kind == Kind::kVelocity || kind == Kind::kYawRate) && !position_jump[k] && std::abs(in) > limit) {
        const double dt = t[k] - t[k - 1];
        const double max_rate = kind == Kind::kVelocity ? o.max_accel_mps2 : o.max_yaw_accel_radps2;
        if (dt > 0 && std::abs(in + med) > max_rate * dt) flag(k, c.name, v[k], "jump");
      }
    }
  }
  std::stable_sort(flags.begin(), flags.end(), [](const ScreenFlag& a, const ScreenFlag& b) { return a.row < b.row; });
  return flags;
}

std::vector<char> screened_rows(std::size_t rows, const std::vector<ScreenFlag>& flags, int guard_rows) {
  std::vector<char> out(rows, 0);
  const std::size_t g = static_cast<std::size_t>(std::max(0, guard_rows));
  for (const ScreenFlag& f : flags) {
    const std::size_t lo = f.row >= g ? f.row - g : 0;
    const std::size_t hi = std::min(rows - 1, f.row + g);
    for (std::size_t k = lo; k <= hi; ++k) out[k] = 1;
  }
  return out;
}

}  // namespace mppi::sysid
