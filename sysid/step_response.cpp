#include "sysid/plant_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "base/error.hpp"

namespace mppi::sysid {

std::vector<double> step_response(const RolloutStep& step, std::vector<double> x, const double u[2],
                                  std::size_t channel, const std::vector<double>& leads_s, double dt_s) {
  if (!(dt_s > 0) || leads_s.empty() || channel >= x.size())
    throw Error("step response: dt_s > 0, at least one lead and a channel of the state are needed");
  std::vector<double> out;
  double t = 0;
  for (double lead : leads_s) {
    for (; t < lead - 0.5 * dt_s; t += dt_s) step(x, u, dt_s);
    out.push_back(x[channel]);
  }
  return out;
}

std::vector<double> steering_step_yaw_rate(const VehicleModelSpec& spec, const std::vector<double>& values,
                                           double speed_mps, double steer, double throttle,
                                           const std::vector<double>& leads_s, double dt_s) {
  if (!(dt_s > 0)) throw Error("steering step: dt_s must be > 0");
  // 1 s of straight driving, then the step: a recording to start (and prime) the plant from.
  const int before = static_cast<int>(std::lround(1.0 / dt_s));
  sim::Recording rec;
  rec.columns = {"t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle"};
  rec.data.assign(rec.columns.size(), {});
  for (int i = 0; i <= before; ++i) {
    const double row[9] = {i * dt_s, speed_mps * i * dt_s, 0, 0, speed_mps, 0, 0, i < before ? 0.0 : steer, throttle};
    for (std::size_t c = 0; c < 9; ++c) rec.data[c].push_back(row[c]);
  }
  const PreparedRecording prepared = prepare(rec, "steering step", 2);
  std::vector<double> x(static_cast<std::size_t>(spec.nx));
  spec.init_state(prepared, static_cast<std::size_t>(before), x.data());
  if (spec.prime) spec.prime(values, prepared, static_cast<std::size_t>(before), x.data());
  const auto m = std::find_if(spec.measurable.begin(), spec.measurable.end(),
                              [](const auto& c) { return c.first == "yaw_rate"; });
  if (m == spec.measurable.end()) throw Error("steering step: the " + spec.kind + " model has no yaw rate");
  const RolloutStep plant = [&](std::vector<double>& s, const double u[2], double dt) {
    spec.step(values, s.data(), u, dt);
  };
  const double u[2] = {steer, throttle};
  return step_response(plant, std::move(x), u, static_cast<std::size_t>(m->second), leads_s, dt_s);
}

}  // namespace mppi::sysid
