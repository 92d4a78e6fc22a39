#include "laptime/register_collocation.hpp"

#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "base/error.hpp"
#include "laptime/min_time_lap.hpp"
#include "sim/limit_lap_methods.hpp"

namespace mppi::laptime {
namespace {

// The flying lap by collocation of a vehicle on a track, solved once per process: the standing
// start starts from it, and a closed-loop run asks for both.
std::shared_ptr<const MinTimeLap> flying_lap(const sim::Track& track, const SingleTrackParams& vehicle) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const MinTimeLap>> cache;
  const std::string key = track.name() + (track.direction() == sim::Direction::kClockwise ? " cw\n" : " ccw\n") +
                          to_yaml(vehicle);
  {
    std::lock_guard lock(mutex);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
  }
  auto lap = std::make_shared<const MinTimeLap>(min_time_lap(track, vehicle));
  std::lock_guard lock(mutex);
  return cache.emplace(key, std::move(lap)).first->second;
}

sim::LimitLap converged_or_throw(const std::shared_ptr<const MinTimeLap>& lap, const sim::Track& track,
                                 const std::string& what) {
  if (!lap->converged)
    throw Error("the " + what + "minimum-time lap by collocation did not converge on " + track.name() + " (IPOPT: " +
                lap->solver_status + " after " + std::to_string(lap->iterations) + " iterations, largest defect " +
                std::to_string(lap->max_defect) + ")");
  return lap->lap;
}

}  // namespace

void register_collocation_limit_lap() {
  sim::register_limit_lap_method("collocation", [](const sim::Track& track, const SingleTrackParams& vehicle,
                                                    sim::LapStart start) {
    if (start == sim::LapStart::kFlying) return converged_or_throw(flying_lap(track, vehicle), track, "");
    // The standing start starts from the flying lap (the same but for its first metres).
    const std::shared_ptr<const MinTimeLap> flying = flying_lap(track, vehicle);
    return converged_or_throw(std::make_shared<const MinTimeLap>(standing_start_lap(
                                  track, vehicle, {}, flying->converged ? flying.get() : nullptr)),
                              track, "standing-start ");
  });
}

}  // namespace mppi::laptime
