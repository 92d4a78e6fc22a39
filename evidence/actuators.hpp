#pragma once
// The evidence car's actuators in their own forms: an exact FIFO delay line, a servo rate
// limit, backlash (play), the steering map, and a battery-fed motor whose torque follows the
// terminal voltage.
#include <deque>
#include <utility>

#include "evidence/car_physics.hpp"
#include "evidence/truth_effects.hpp"

namespace mppi::evidence {

// Pure delay: value(t) = the command issued last at or before t - delay (exact for commands
// held between issue times).
class DelayLine {
 public:
  explicit DelayLine(double delay_s = 0) : delay_s_(delay_s) {}
  void issue(double t_s, double value);
  double value(double t_s);
  void reset() { queue_.clear(); }

 private:
  double delay_s_;
  std::deque<std::pair<double, double>> queue_;  // (issue time, value), ascending
};

// Servo: moves towards its target at no more than rate [1/s] (rate <= 0: instantly).
double rate_limited(double current, double target, double rate_per_s, double dt_s);

// Backlash of width b: the output stays put while the input moves inside the play
// [out - b/2, out + b/2] and is dragged along by the edge beyond it.
double backlash(double output, double input, double width);

// The DC motor behind a battery: torque = stall (u V / V_nom - omega R / v_0) for u >= 0 with
// V = V_oc(q) - R I, I proportional to the torque (solved in closed form); braking (u < 0)
// is the plain line with the command scaled: stall (brake_torque_ratio u - omega R / v_0).
// `charge_used` [stall-current seconds] grows with the current.
struct Battery {
  double internal_resistance_fraction = 0, capacity_sag = 0, charge_used = 0;
  double torque_Nm(const CarConstants& c, double throttle, double rear_rim_mps) const;
  void draw(const CarConstants& c, double torque_Nm, double dt_s);
};

// A firmware speed loop (ESC / motor controller in speed mode): the command u asks for the speed
// top_speed u; a PI controller on the motor's rim speed sets the throttle, its integral held
// while the output is at a limit (anti-windup).
struct SpeedLoop {
  double top_speed_mps = 0, kp_per_mps = 0, ki_per_m = 0, integral = 0;
  bool active() const { return top_speed_mps > 0; }
  double throttle(double command, double rim_mps, double dt_s);
};

// All of the car's actuation for one physics step.
class ActuatorChain {
 public:
  ActuatorChain(const TruthEffects& e, const CarConstants& c);
  void issue(double t_s, double steer_command, double throttle_command);
  // Advances the servo by dt_s to time t_s and returns (wheel angle [rad], motor torque [N m]).
  std::pair<double, double> step(double t_s, double dt_s, double rear_rim_mps);
  void reset();  // after a respawn: everything at rest (the battery keeps its charge state)
  double servo_position() const { return servo_; }
  double wheel_command() const { return wheel_; }

 private:
  TruthEffects e_;
  CarConstants c_;
  DelayLine steer_delay_, throttle_delay_;
  double servo_ = 0, wheel_ = 0;
  Battery battery_;
  SpeedLoop speed_loop_;
};

}  // namespace mppi::evidence
