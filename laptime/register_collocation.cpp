#include "laptime/register_collocation.hpp"

#include "base/error.hpp"
#include "laptime/min_time_lap.hpp"
#include "sim/limit_lap_methods.hpp"

namespace mppi::laptime {

void register_collocation_limit_lap() {
  sim::register_limit_lap_method("collocation", [](const sim::Track& track, const SingleTrackParams& vehicle) {
    MinTimeLap lap = min_time_lap(track, vehicle);
    if (!lap.converged)
      throw Error("the minimum-time lap by collocation did not converge on " + track.name() + " (IPOPT: " +
                  lap.solver_status + " after " + std::to_string(lap.iterations) + " iterations)");
    return std::move(lap.lap);
  });
}

}  // namespace mppi::laptime
