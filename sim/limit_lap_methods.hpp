#pragma once
// Limit-lap methods by name, so that the closed loop and mppi-sim can measure laps against a
// method that lives in a library above sim/: "qss" (sim/limit_lap.hpp, the quasi-steady-state lap
// on a racing line; both starts solved together and kept per track name, direction and vehicle in a
// process) is always there; laptime/ registers "collocation" (the minimum-time lap of the
// single-track model's own equations, solved with IPOPT) where it is built.
#include <functional>
#include <string>
#include <vector>

#include "dynamics/vehicle_params.hpp"
#include "sim/limit_lap.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

// A flying lap (periodic: it ends at the speed it starts) or a standing start (from rest at the
// track's start line once round to it, as the closed loop's first lap).
enum class LapStart { kFlying, kStanding };

using LimitLapMethod = std::function<LimitLap(const Track&, const SingleTrackParams&, LapStart)>;

// Adds or replaces a method. Thread-safe.
void register_limit_lap_method(const std::string& name, LimitLapMethod method);

// The limit lap by the named method. Throws mppi::Error for an unknown name (listing the known
// ones) and whatever the method throws.
LimitLap limit_lap_by_method(const std::string& name, const Track& track, const SingleTrackParams& vehicle,
                             LapStart start = LapStart::kFlying);

// Throws mppi::Error for a name that is not registered, listing the known ones.
void require_limit_lap_method(const std::string& name);

// The registered names, "qss" first.
std::vector<std::string> limit_lap_method_names();

}  // namespace mppi::sim
