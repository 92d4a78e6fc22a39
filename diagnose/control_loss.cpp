#include "diagnose/control_loss.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "base/error.hpp"

namespace mppi::diagnose {

std::vector<char> control_loss_rows(const PreparedRecording& d, const ControlLossOptions& o) {
  if (!(o.max_body_slip_deg >= 0 && o.max_body_slip_deg <= 90) || !(o.min_speed_mps >= 0) || !std::isfinite(o.min_speed_mps) ||
      !(o.guard_s >= 0) || !std::isfinite(o.guard_s)) {
    char why[200];
    std::snprintf(why, sizeof why, "a body slip limit in [0, 90] deg (0: off), a speed >= 0 and a guard >= 0 s; got %g deg, %g m/s, %g s",
                  o.max_body_slip_deg, o.min_speed_mps, o.guard_s);
    throw Error(d.source + ": lost-control options need " + why);
  }
  const std::size_t n = d.rows();
  std::vector<char> out(n, 0);
  if (o.max_body_slip_deg == 0 || n == 0) return out;
  const double limit_rad = o.max_body_slip_deg * std::numbers::pi / 180.0;
  const std::ptrdiff_t guard = static_cast<std::ptrdiff_t>(std::lround(o.guard_s / d.dt_s));
  for (std::size_t k = 0; k < n; ++k) {
    const double speed = std::hypot(d.vx[k], d.vy[k]);
    if (!(speed > o.min_speed_mps)) continue;
    const double slip = std::atan2(std::abs(d.vy[k]), std::abs(d.vx[k]));  // in [0, pi/2]: reversing folded
    if (!(slip > limit_rad)) continue;
    const std::ptrdiff_t k0 = std::max<std::ptrdiff_t>(0, static_cast<std::ptrdiff_t>(k) - guard);
    const std::ptrdiff_t k1 = std::min<std::ptrdiff_t>(static_cast<std::ptrdiff_t>(n) - 1, static_cast<std::ptrdiff_t>(k) + guard);
    std::fill(out.begin() + k0, out.begin() + k1 + 1, 1);
  }
  return out;
}

}  // namespace mppi::diagnose
