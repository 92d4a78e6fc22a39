#pragma once
// The single-track's actuators as the calibration models them (the steering servo and the drive's
// response; the same terms as the effects steer_lag, throttle_lag, steer_cubic and steer_offset of
// WithEffects, dynamics/effects.hpp): first-order lags of the commands, then the steering map
// s -> s + k s^3 + offset.
#include <cmath>

#include "dynamics/vehicle_params.hpp"

namespace mppi::sysid::detail {

struct Actuators {
  double steer_lag_s = 0;     // [s] first-order time constant of the steering servo
  double throttle_lag_s = 0;  // [s] first-order time constant of the drive
  double steer_cubic = 0;     // [-] k in s -> s + k s^3
  double steer_offset = 0;    // [-] added to the applied steer
};
struct SingleTrackWithActuators {
  SingleTrackParams car;
  Actuators act;
};
constexpr double kActuatorPrime_s = 1.0;  // command history run through the lags before a start

// Advances the two lag states y (steer, throttle) over h with commands u held: y += (1 - e^(-h/tau)) (u - y).
inline void advance_actuators(const Actuators& a, const double* u, double h, double* y) {
  const double as = a.steer_lag_s > 0 ? 1 - std::exp(-h / a.steer_lag_s) : 1.0;
  const double at = a.throttle_lag_s > 0 ? 1 - std::exp(-h / a.throttle_lag_s) : 1.0;
  y[0] += as * (u[0] - y[0]);
  y[1] += at * (u[1] - y[1]);
}
inline double applied_steer(const Actuators& a, double s) { return s + a.steer_cubic * s * s * s + a.steer_offset; }

}  // namespace mppi::sysid::detail
