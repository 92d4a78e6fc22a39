#pragma once
// The single-track model (dynamics/single_track.hpp) in the track's curvilinear frame, with arc
// length along the centreline as the independent variable: the right-hand side the minimum-time
// collocation (laptime/min_time_lap.hpp) integrates between stations.
#include <cmath>

#include "dynamics/single_track.hpp"

namespace mppi::laptime {

// Layout of one station's variables.
namespace var {
constexpr int kOffset = 0;        // n [m], along the centreline's left normal
constexpr int kHeadingError = 1;  // xi [rad], heading minus the centreline's
constexpr int kVx = 2;            // body velocities [m/s], yaw rate [rad/s]
constexpr int kVy = 3;
constexpr int kYawRate = 4;
constexpr int kOmegaFront = 5;    // wheel speeds [rad/s]
constexpr int kOmegaRear = 6;
constexpr int kSteer = 7;         // commands in [-1, 1]
constexpr int kThrottle = 8;
constexpr int kCount = 9;
constexpr int kStates = 7;        // the first seven are states, the last two commands
}  // namespace var

// ds/dt: the speed of the car's projection on the centreline [m/s] (curvature kappa_1pm there).
inline double centreline_speed_mps(const double* z, double kappa_1pm) {
  const double sx = std::sin(z[var::kHeadingError]), cx = std::cos(z[var::kHeadingError]);
  return (z[var::kVx] * cx - z[var::kVy] * sx) / (1.0 - z[var::kOffset] * kappa_1pm);
}

// d(state)/ds at one station, the seven states of `z` (var::kStates values into dz_ds).
inline void spatial_derivative(const SingleTrackCoeffs<double>& k, const double* z, double kappa_1pm,
                               double* dz_ds) {
  SingleTrackTerms<double> e;
  single_track_terms(k, z[var::kVx], z[var::kVy], z[var::kYawRate], z[var::kOmegaFront], z[var::kOmegaRear],
                     z[var::kSteer], z[var::kThrottle], &e);
  const double sx = std::sin(z[var::kHeadingError]), cx = std::cos(z[var::kHeadingError]);
  const double inv_sdot = 1.0 / centreline_speed_mps(z, kappa_1pm);
  dz_ds[var::kOffset] = (z[var::kVx] * sx + z[var::kVy] * cx) * inv_sdot;
  dz_ds[var::kHeadingError] = z[var::kYawRate] * inv_sdot - kappa_1pm;
  dz_ds[var::kVx] = e.dvx_mps2 * inv_sdot;
  dz_ds[var::kVy] = e.dvy_mps2 * inv_sdot;
  dz_ds[var::kYawRate] = e.dyaw_rate_radps2 * inv_sdot;
  dz_ds[var::kOmegaFront] = e.domega_front_radps2 * inv_sdot;
  dz_ds[var::kOmegaRear] = e.domega_rear_radps2 * inv_sdot;
}

}  // namespace mppi::laptime
