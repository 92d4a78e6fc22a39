#pragma once
// The single-track car's minimum-time lap by direct collocation of its own equations
// (dynamics/single_track.hpp: Pacejka tyres with combined slip, wheel spin, pitch load transfer,
// drive and brake lines, drag), solved with IPOPT. Where the quasi-steady-state lap
// (sim/limit_lap.hpp) assumes that the car can hold any curvature at the tyres' peak friction,
// this lap is one the car's equations can drive: the yaw dynamics, the rear tyre's drive force
// while cornering and the steering's range are in it.
//
// Formulation (docs/LIMIT_LAP.md): arc length s along the track's centreline is the independent
// variable. The state at each station is the offset n along the centreline's left normal, the
// heading relative to the centreline xi, the body velocities vx, vy, the yaw rate r and the wheel
// speeds; the controls are steer and throttle in [-1, 1]. With kappa the centreline's curvature,
//   ds/dt = (vx cos xi - vy sin xi) / (1 - n kappa),
//   dn/ds = (vx sin xi + vy cos xi) / (ds/dt),   dxi/ds = r / (ds/dt) - kappa,
//   d(vx, vy, r, omega_f, omega_r)/ds = f(x, u) / (ds/dt),
// trapezoidal collocation between stations (closed: the last station joins the first), the lap
// time sum ds / (ds/dt) the objective, the offsets bounded by the half-widths less the margin.
// The start is the racing line's QSS lap (sim/limit_lap.hpp). Jacobians by central differences of
// the model (the model's own double-precision code); the Hessian by IPOPT's limited-memory
// quasi-Newton update.
#include <string>
#include <vector>

#include "dynamics/vehicle_params.hpp"
#include "sim/limit_lap.hpp"
#include "sim/track.hpp"

namespace mppi::laptime {

struct MinTimeLapOptions {
  double car_half_width_m = 0.3;    // as sim::LimitLapOptions: the centre of gravity keeps
  double safety_margin_m = 0.2;     // half the car's width plus this from both boundaries
  double station_spacing_m = 0.5;   // collocation stations along the centreline [m]
  // Added to the lap time [s per (command unit)^2 per station]: damps the chattering of the
  // commands between stations that the lap time alone leaves free; small enough to move the lap
  // by well under a millisecond.
  double command_smoothing_s = 1e-4;
  int max_iterations = 3000;        // IPOPT iterations
  double tolerance = 1e-6;          // IPOPT's relative tolerance
  // The largest defect (state units: m, rad, m/s, rad/s) of a solution called converged; IPOPT may
  // stop at its acceptable level (lap time settled to 1e-6 relative) when the defects are below it.
  double max_defect = 1e-3;
  bool verbose = false;             // IPOPT's iteration log on stdout
  // Standing start (standing_start_lap): ds/dt = 0 at rest makes the spatial equations singular,
  // so the first station is where the car, launched from rest at the start line at the car's
  // maximal drive acceleration (launch_from_rest), reaches this speed [m/s]; the launch's time is
  // added in closed form. The stations after it grow geometrically by this ratio until they reach
  // station_spacing_m, so that the trapezoid in 1 / speed stays accurate while the speed climbs.
  double launch_speed_mps = 1.0;
  double launch_station_ratio = 1.2;
};

struct MinTimeLap {
  sim::LimitLap lap;                // the path, speed and accelerations per station (QSS's shape)
  bool converged = false;           // IPOPT reached its tolerance
  std::string solver_status;        // IPOPT's word for how it stopped
  int iterations = 0;
  double max_defect = 0.0;          // largest |defect| of the returned solution
  double qss_lap_time_s = 0.0;      // the start: the racing line's QSS lap
  // Per station: the solution's states and commands.
  std::vector<double> offset_m, heading_error_rad, yaw_rad, vx_mps, vy_mps, yaw_rate_radps;
  std::vector<double> omega_front_radps, omega_rear_radps, steer, throttle, time_s;
  // Largest |body slip angle| atan2(vy, vx) along the lap [rad].
  double max_body_slip_rad = 0.0;
};

// The run from rest to a speed at the car's maximal drive acceleration on a straight: the driven
// axle at its tyre's peak friction mu_R (sim::tyre_peak_friction) under the model's quasi-static
// pitch transfer, for rear-wheel drive G = mu_R m g l_f / (L - h mu_R) (dynamics/single_track.hpp
// with the front wheel rolling; a car with front drive gets sim::car_limits' static grip), less
// rolling resistance and drag: m dv/dt = G - c v^2 with c = aero_drag_kgpm, in closed form
//   t = m / sqrt(G c) atanh(v sqrt(c / G)),   x = m / (2 c) ln(G / (G - c v^2))
// (t = m v / G, x = m v^2 / (2 G) without drag).
struct Launch {
  double time_s = 0.0;
  double distance_m = 0.0;
};
// Throws mppi::Error where the launch is not grip-limited up to that speed (the motor's line
// below the grip: the closed form does not hold) or the grip does not beat the resistances.
Launch launch_from_rest(const SingleTrackParams& vehicle, double speed_mps);


// Throws mppi::Error for bad options or parameters (naming them), a track too narrow for the
// margin, or a solver that fails to start. A solve that stops short of the tolerance is returned
// with converged = false and its status (the caller decides whether to trust it).
MinTimeLap min_time_lap(const sim::Track& track, const SingleTrackParams& vehicle,
                        const MinTimeLapOptions& options = {});

// The minimum-time lap from a standing start: the car at rest at the track's start pose (centreline
// vertex 0, facing along the track: where the closed loop spawns it) once round to the start line
// (where the closed loop counts the lap), the end state free. The same collocation, open: the first
// station, options.launch_speed_mps past rest (at the launch's distance from the line), is fixed at
// the start pose's offset and heading, that speed straight ahead, no yaw rate and rolling wheels;
// the last station is the start line. lap.lap_time_s includes the launch (lap.launch_time_s).
// The result's per-station vectors have one entry per station of the open problem, the last on the
// start line. IPOPT starts from `flying` where given (min_time_lap's solution with the same
// options: the standing lap is the flying one but for its first metres), slowed to the QSS lap
// from rest where that is slower; else from the QSS lap from rest on the racing line. Throws as
// min_time_lap, for a launch speed below 0.5 m/s or one whose launch does not fit before the
// second station, and for a flying lap on other stations.
MinTimeLap standing_start_lap(const sim::Track& track, const SingleTrackParams& vehicle,
                              const MinTimeLapOptions& options = {}, const MinTimeLap* flying = nullptr);

}  // namespace mppi::laptime
