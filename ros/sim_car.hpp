#pragma once
// The simulated car behind the simulator node, without ROS: the single-track plant behind
// rate-limited actuators with optional pure delays (sim/plant.hpp), the chassis interface
// (chassis/sim_adapter.hpp: priorities, runstop, watchdog, calibration), lap counting and crash
// detection on a built-in track; a crashed car is put back on the centreline at rest, as in
// mppi-sim (sim/closed_loop.cpp). The node integrates it in real time, feeding the commands as
// they come. C++17 header (the ROS 1 nodes are C++17; ros/controller_setup.hpp says why).
#include <memory>
#include <string>
#include <vector>

#include "mppi/vehicle_state.hpp"

namespace mppi::ros {

struct SimCarSettings {
  std::string track = "gazebo";
  std::string plant_params;          // single-track parameters (YAML); empty = data/config default
  double plant_dt_s = 0.002;         // integration step
  double steering_delay_s = 0.0;     // pure transport delay of the steering command
  double throttle_delay_s = 0.0;     // and of the throttle command
  // The actuators' rate limits [1/s] (sim::ActuatorLimits' defaults: a servo needs 0.4 s lock to
  // lock); a large value (1e4) makes them act at once, as the diagnosis' nominal models do.
  double steering_rate_per_s = 5.0;
  double throttle_rate_per_s = 10.0;

  bool is_valid(std::string* why) const;
};

class SimCar {
 public:
  explicit SimCar(const SimCarSettings& settings);  // throws mppi::Error naming the fault
  ~SimCar();
  SimCar(const SimCar&) = delete;
  SimCar& operator=(const SimCar&) = delete;

  // A controller's command at time t_s (chassis time): enters the chassis' arbiter.
  void command(const Control& u, double t_s);
  // The operator's runstop.
  void set_motion_enabled(bool enabled);
  // Integrates up to t_s with what the chassis applies; counts laps and crashes.
  void advance_to(double t_s);

  double time_s() const;
  VehicleState state() const;
  Control applied() const;                  // the actuators' positions
  bool motion_enabled() const;              // the chassis' runstop decision
  std::string steering_commander() const;   // who sets the steering (a controller, runstop, watchdog)
  std::string throttle_commander() const;
  int laps_completed() const;
  const std::vector<double>& lap_times_s() const;
  int crashes() const;
  // {"laps": N, "lap_times_s": [...], "crashes": N, "crash_reasons": [...], "sim_time_s": T}
  std::string summary_json() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mppi::ros
