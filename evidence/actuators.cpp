#include "evidence/actuators.hpp"

#include <algorithm>
#include <cmath>

namespace mppi::evidence {

void DelayLine::issue(double t_s, double value) { queue_.emplace_back(t_s, value); }

double DelayLine::value(double t_s) {
  const double due = t_s - delay_s_ + 1e-9;
  while (queue_.size() > 1 && queue_[1].first <= due) queue_.pop_front();
  if (queue_.empty() || queue_.front().first > due) return 0.0;  // nothing issued yet: at rest
  return queue_.front().second;
}

double rate_limited(double current, double target, double rate_per_s, double dt_s) {
  if (rate_per_s <= 0) return target;
  const double step = rate_per_s * dt_s;
  return current + std::clamp(target - current, -step, step);
}

double backlash(double output, double input, double width) {
  const double half = width / 2;
  if (input > output + half) return input - half;
  if (input < output - half) return input + half;
  return output;
}

double Battery::torque_Nm(const CarConstants& c, double throttle, double rear_rim_mps) const {
  const double back_emf = rear_rim_mps / c.no_load_speed_mps;
  if (throttle <= 0) return c.stall_torque_Nm * (c.brake_torque_ratio * throttle - back_emf);
  const double open_circuit = std::max(0.0, 1 - capacity_sag * charge_used / 60.0);
  const double t = c.stall_torque_Nm * (throttle * open_circuit - back_emf);
  // With I = torque / stall torque x I_stall and V = V_oc - R I: t (1 + a u) = stall (u v_oc - emf).
  return t > 0 ? t / (1 + internal_resistance_fraction * throttle) : t;
}

void Battery::draw(const CarConstants& c, double torque_Nm, double dt_s) {
  charge_used += std::max(0.0, torque_Nm) / c.stall_torque_Nm * dt_s;
}

double SpeedLoop::throttle(double command, double rim_mps, double dt_s) {
  const double error_mps = top_speed_mps * command - rim_mps;
  const double wound = integral + error_mps * dt_s;
  const double out = kp_per_mps * error_mps + ki_per_m * wound;
  if (out > -1 && out < 1) integral = wound;  // anti-windup: no integration at a limit
  return std::clamp(kp_per_mps * error_mps + ki_per_m * integral, -1.0, 1.0);
}

ActuatorChain::ActuatorChain(const TruthEffects& e, const CarConstants& c)
    : e_(e), c_(c), steer_delay_(e.steer_delay_s), throttle_delay_(e.throttle_delay_s) {
  battery_.internal_resistance_fraction = e.battery_internal_resistance_fraction;
  battery_.capacity_sag = e.battery_capacity_sag;
  speed_loop_.top_speed_mps = e.speed_loop_top_speed_mps;
  speed_loop_.kp_per_mps = e.speed_loop_kp;
  speed_loop_.ki_per_m = e.speed_loop_ki;
}

void ActuatorChain::issue(double t_s, double steer_command, double throttle_command) {
  steer_delay_.issue(t_s, std::clamp(steer_command, -1.0, 1.0));
  throttle_delay_.issue(t_s, std::clamp(throttle_command, -1.0, 1.0));
}

std::pair<double, double> ActuatorChain::step(double t_s, double dt_s, double rear_rim_mps) {
  const double s = steer_delay_.value(t_s);
  const double mapped = e_.steer_gain * s + e_.steer_cubic * s * s * s + e_.steer_offset;
  servo_ = rate_limited(servo_, mapped, e_.steer_rate_per_s, dt_s);
  wheel_ = backlash(wheel_, servo_, e_.steer_backlash);
  double command = throttle_delay_.value(t_s);
  if (speed_loop_.active()) command = speed_loop_.throttle(command, rear_rim_mps, dt_s);
  const double u = std::clamp(e_.throttle_gain * command, -1.0, 1.0);
  const double torque = battery_.torque_Nm(c_, u, rear_rim_mps);
  battery_.draw(c_, torque, dt_s);
  return {std::clamp(wheel_, -1.0, 1.0) * c_.max_steer_rad, torque};
}

void ActuatorChain::reset() {
  steer_delay_.reset();
  throttle_delay_.reset();
  servo_ = wheel_ = 0;
  speed_loop_.integral = 0;
}

}  // namespace mppi::evidence
