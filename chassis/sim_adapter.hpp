#pragma once
// The built-in simulator behind the chassis interface. Each control period the controller's
// output goes in as a command from `controller`, a simulated operator (`runstop_source`)
// sends a runstop message allowing motion, the chassis decides (priorities, runstop,
// watchdog) and calibrates to pulse widths; the simulated car's servos turn the pulse widths
// back into normalised actuator positions. Time is the simulation's (a fake clock), so runs
// stay deterministic. With a calibration of whole microseconds the pulse -> value inverse is
// exact for every float command of magnitude >= 2^-26 (smaller ones come back within 1e-15),
// so the plant sees what the controller sent (tests/chassis/test_sim_adapter.cpp).
#include <string>

#include "chassis/chassis.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi::chassis {

struct SimChassisSettings {
  Calibration calibration;                   // default: AutoRally's 1000/1500/2000 us
  std::string controller = "mppi";           // the controller's sender name
  std::string runstop_source = "simulator";  // the simulated operator's runstop
  bool motion_enabled = true;                // what the simulated operator's runstop says
  SafetySettings safety;
};

class SimChassis {
 public:
  explicit SimChassis(SimChassisSettings settings = {});

  // One control period at simulated time t_s: publish `u` and return the actuator values the
  // chassis applies (the plant's command). A rejected u (NaN, out of range) changes nothing:
  // the previous command holds until it is stale, then the watchdog neutralises.
  Control drive(const Control& u, double t_s);
  // The chassis output at t_s without a new command (for plants integrated between commands).
  Control hold(double t_s);
  // Simulated operator: allow or stop autonomous motion from now on.
  void set_motion_enabled(bool enabled) { settings_.motion_enabled = enabled; }

  const ChassisOutput& last_output() const { return last_; }
  const Arbiter& arbiter() const { return chassis_.arbiter(); }

 private:
  Control apply(Time now);

  SimChassisSettings settings_;
  Chassis chassis_;
  int controller_index_;
  ChassisOutput last_;
};

}  // namespace mppi::chassis
