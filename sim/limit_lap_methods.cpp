#include "sim/limit_lap_methods.hpp"

#include <algorithm>
#include <map>
#include <mutex>

#include "base/error.hpp"

namespace mppi::sim {
namespace {

struct Registry {
  std::mutex mutex;
  std::map<std::string, LimitLapMethod> methods{
      {"qss", [](const Track& track, const SingleTrackParams& vehicle) { return limit_lap(track, vehicle); }}};
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

LimitLap limit_lap_by_method(const std::string& name, const Track& track, const SingleTrackParams& vehicle) {
  LimitLapMethod method;
  {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    auto it = r.methods.find(name);
    if (it != r.methods.end()) method = it->second;
  }
  if (!method) require_limit_lap_method(name);  // throws, naming the known methods
  return method(track, vehicle);
}

}  // namespace mppi::sim
