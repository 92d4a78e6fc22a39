#include "chassis/sim_adapter.hpp"

namespace mppi::chassis {

SimChassis::SimChassis(SimChassisSettings settings)
    : settings_(std::move(settings)),
      chassis_(Priorities({{settings_.controller, 0}}), settings_.calibration, settings_.safety),
      controller_index_(0) {}

Control SimChassis::drive(const Control& u, double t_s) {
  const Time now = seconds(t_s);
  chassis_.arbiter().submit_runstop(settings_.runstop_source, settings_.motion_enabled, now);
  chassis_.arbiter().submit_command(controller_index_, Command{u.steer, u.throttle, 0.f, actuator::kAll},
                                    now);
  return apply(now);
}

Control SimChassis::hold(double t_s) { return apply(seconds(t_s)); }

Control SimChassis::apply(Time now) {
  last_ = chassis_.update(now);
  // The simulated servos: pulse widths back to normalised positions. The plant has no front
  // brake; its value is only logged in the pulse widths.
  const Command applied = chassis_.calibration().values(last_.pulses);
  return Control{applied.steering, applied.throttle};
}

}  // namespace mppi::chassis
