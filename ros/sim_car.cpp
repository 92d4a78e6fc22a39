#include "ros/sim_car.hpp"

#include <cmath>
#include <cstdio>

#include "base/error.hpp"
#include "chassis/sim_adapter.hpp"
#include "dynamics/single_track.hpp"
#include "dynamics/vehicle_params.hpp"
#include "sim/centreline_pose.hpp"
#include "sim/crash_detector.hpp"
#include "sim/data_dir.hpp"
#include "sim/geometry.hpp"
#include "sim/lap_counter.hpp"
#include "sim/plant.hpp"
#include "sim/track.hpp"

namespace mppi::ros {
namespace {

sim::ActuatorLimits limits_of(const SimCarSettings& s) {
  std::string why;
  if (!s.is_valid(&why)) throw Error("simulator node parameters: " + why);
  sim::ActuatorLimits a;
  a.steer_delay_s = static_cast<float>(s.steering_delay_s);
  a.throttle_delay_s = static_cast<float>(s.throttle_delay_s);
  a.steer_rate_per_s = static_cast<float>(s.steering_rate_per_s);
  a.throttle_rate_per_s = static_cast<float>(s.throttle_rate_per_s);
  return a;
}

std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

}  // namespace

bool SimCarSettings::is_valid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(plant_dt_s > 0.0 && plant_dt_s <= 0.02)) return fail("plant_dt_s must be in (0, 0.02]");
  if (!(steering_delay_s >= 0.0 && steering_delay_s < 10.0)) return fail("steering_delay_s must be in [0, 10)");
  if (!(throttle_delay_s >= 0.0 && throttle_delay_s < 10.0)) return fail("throttle_delay_s must be in [0, 10)");
  if (!(steering_rate_per_s > 0.0 && steering_rate_per_s <= 1e6)) return fail("steering_rate_per_s must be in (0, 1e6]");
  if (!(throttle_rate_per_s > 0.0 && throttle_rate_per_s <= 1e6)) return fail("throttle_rate_per_s must be in (0, 1e6]");
  return true;
}

struct SimCar::Impl {
  explicit Impl(const SimCarSettings& s)
      : track(sim::Track::load(s.track)),
        plant(SingleTrack(load_single_track_params(
                  s.plant_params.empty() ? sim::data_file("config/autorally_single_track.yaml") : s.plant_params)),
              limits_of(s), static_cast<float>(s.plant_dt_s)),
        laps(track),
        crash_detector(track),
        plant_dt_s(s.plant_dt_s) {}

  void put_back() {
    const VehicleState s = plant.vehicle_state();
    const sim::Pose2 p = sim::centreline_pose_nearest(track, {s.x_m, s.y_m});
    VehicleState respawn;
    respawn.x_m = static_cast<float>(p.x_m);
    respawn.y_m = static_cast<float>(p.y_m);
    respawn.yaw_rad = static_cast<float>(p.yaw_rad);
    plant.reset(respawn);
  }

  sim::Track track;
  sim::Plant<SingleTrack> plant;
  chassis::SimChassis chassis;
  sim::LapCounter laps;
  sim::CrashDetector crash_detector;
  double plant_dt_s;
  double t_s = 0.0;
  bool in_contact = false;
  bool have_command = false;
  std::vector<std::string> crash_reasons;
};

SimCar::SimCar(const SimCarSettings& s) : impl_(std::make_unique<Impl>(s)) {
  const sim::Pose2 start = impl_->track.start_pose();
  VehicleState s0;
  s0.x_m = static_cast<float>(start.x_m);
  s0.y_m = static_cast<float>(start.y_m);
  s0.yaw_rad = static_cast<float>(start.yaw_rad);
  impl_->plant.reset(s0);
  impl_->laps.reset({start.x_m, start.y_m}, 0.0);
}

SimCar::~SimCar() = default;

void SimCar::command(const Control& u, double t_s) {
  impl_->chassis.drive(u, t_s);
  impl_->have_command = true;
}

void SimCar::set_motion_enabled(bool enabled) { impl_->chassis.set_motion_enabled(enabled); }

void SimCar::advance_to(double t_s) {
  Impl& d = *impl_;
  while (d.t_s + 0.5 * d.plant_dt_s < t_s) {
    const Control applied = d.have_command ? d.chassis.hold(d.t_s) : Control{};
    d.plant.advance(applied, static_cast<float>(d.plant_dt_s));
    d.t_s += d.plant_dt_s;
    const VehicleState s = d.plant.vehicle_state();
    if (!std::isfinite(s.x_m) || !std::isfinite(s.vx_mps))
      throw Error("simulated car: the plant state became non-finite at t = " + std::to_string(d.t_s) + " s");
    d.laps.update({s.x_m, s.y_m}, d.t_s);
    const sim::CrashResult crash = d.crash_detector.check(s.x_m, s.y_m, s.yaw_rad);
    if (crash.crashed && !d.in_contact) {
      d.crash_reasons.push_back(crash.reason);
      d.put_back();
      d.in_contact = false;
      continue;
    }
    d.in_contact = crash.crashed;
  }
}

double SimCar::time_s() const { return impl_->t_s; }
VehicleState SimCar::state() const { return impl_->plant.vehicle_state(); }
Control SimCar::applied() const { return impl_->plant.applied(); }
bool SimCar::motion_enabled() const { return impl_->chassis.last_output().decision.motion_enabled; }
std::string SimCar::steering_commander() const {
  return std::string(impl_->chassis.arbiter().commander_name(impl_->chassis.last_output().decision.steering_commander));
}
std::string SimCar::throttle_commander() const {
  return std::string(impl_->chassis.arbiter().commander_name(impl_->chassis.last_output().decision.throttle_commander));
}
int SimCar::laps_completed() const { return impl_->laps.laps_completed(); }
const std::vector<double>& SimCar::lap_times_s() const { return impl_->laps.lap_times_s(); }
int SimCar::crashes() const { return static_cast<int>(impl_->crash_reasons.size()); }

std::string SimCar::summary_json() const {
  const Impl& d = *impl_;
  std::string j = "{\"laps\": " + std::to_string(laps_completed()) + ", \"lap_times_s\": [";
  char buf[32];
  for (std::size_t i = 0; i < lap_times_s().size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s%.3f", i ? ", " : "", lap_times_s()[i]);
    j += buf;
  }
  j += "], \"crashes\": " + std::to_string(crashes()) + ", \"crash_reasons\": [";
  for (std::size_t i = 0; i < d.crash_reasons.size(); ++i) j += (i ? ", " : "") + quoted(d.crash_reasons[i]);
  std::snprintf(buf, sizeof buf, "%.3f", d.t_s);
  j += "], \"sim_time_s\": " + std::string(buf) + "}\n";
  return j;
}

}  // namespace mppi::ros
