#include "sim/limit_lap_methods.hpp"

#include <algorithm>
#include <map>
#include <mutex>

#include "base/error.hpp"

namespace mppi::sim {
namespace {

// Both QSS laps from one set of racing lines, kept per track (by name and direction) and vehicle:
// a closed-loop run asks for the flying lap, then the standing start.
LimitLap qss_limit_lap(const Track& track, const SingleTrackParams& vehicle, LapStart start) {
  static std::mutex mutex;
  static std::map<std::string, QssLimitLaps> cache;
  const std::string key = track.name() + (track.direction() == Direction::kClockwise ? " cw\n" : " ccw\n") +
                          to_yaml(vehicle);
  std::lock_guard lock(mutex);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, flying_and_standing_limit_laps(track, vehicle)).first;
  return start == LapStart::kStanding ? it->second.standing : it->second.flying;
}

struct Registry {
  std::mutex mutex;
  std::map<std::string, LimitLapMethod> methods{{"qss", qss_limit_lap}};
};

Registry& registry() {
  static Registry r;
  return r;
}

}  // namespace

void register_limit_lap_method(const std::string& name, LimitLapMethod method) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.methods[name] = std::move(method);
}

std::vector<std::string> limit_lap_method_names() {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  std::vector<std::string> names{"qss"};
  for (const auto& [name, method] : r.methods)
    if (name != "qss") names.push_back(name);
  return names;
}

void require_limit_lap_method(const std::string& name) {
  const std::vector<std::string> names = limit_lap_method_names();
  if (std::find(names.begin(), names.end(), name) != names.end()) return;
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown limit-lap method '" + name + "' (known here: " + known +
              "; 'collocation' needs the build with IPOPT, coinor-libipopt-dev)");
}

LimitLap limit_lap_by_method(const std::string& name, const Track& track, const SingleTrackParams& vehicle,
                             LapStart start) {
  LimitLapMethod method;
  {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    auto it = r.methods.find(name);
    if (it != r.methods.end()) method = it->second;
  }
  if (!method) require_limit_lap_method(name);  // throws, naming the known methods
  return method(track, vehicle, start);
}

}  // namespace mppi::sim
