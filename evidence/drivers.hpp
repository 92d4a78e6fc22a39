#pragma once
// The evidence generator's drivers (50 Hz): pure pursuit with steering dither and a random
// target-speed schedule; and a human-like driver that slows for the curvature ahead with its own
// cornering nerve, reacts late and steers with a slow, imperfect hand, eases onto the throttle and
// lifts when the car yaws faster than the road bends (the rear stepping out). Both use only what
// a driver sees or feels: the car's pose, speed and yaw rate, and the track's centreline.
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "sim/track.hpp"

namespace mppi::evidence {

struct DriverView {
  double t_s, x_m, y_m, yaw_rad, speed_mps;
  double yaw_rate_radps = 0;  // felt, not used by the pursuit driver
};

class Driver {
 public:
  // kind: "pursuit" or "human". Throws mppi::Error for another kind.
  // period_s: how often command() is called (the driver's and the log's rate); the integrator,
  // the human's reaction delay, hand smoothing and pedal rate are in seconds, so the same driver
  // at another rate.
  Driver(const std::string& kind, const sim::Track& track, std::uint64_t seed, double speed_min_mps,
         double speed_max_mps, double wheelbase_m, double max_steer_rad, double period_s = 0.02);
  // (steer, throttle) in [-1, 1].
  std::pair<double, double> command(const DriverView& v);
  void respawned();  // after a crash: forget the integrator and the hint
  const std::string& kind() const { return kind_; }

 private:
  double target_speed(const DriverView& v, double arc_m);
  double curvature_ahead(double arc_m, double distance_m) const;

  std::string kind_;
  double period_s_;
  const sim::Track& track_;
  std::mt19937_64 rng_;
  double speed_min_, speed_max_, wheelbase_, max_steer_;
  std::size_t hint_ = 0;
  bool have_hint_ = false;
  double integral_ = 0;
  // pursuit: speed schedule and dither
  double schedule_speed_ = 5, schedule_until_s_ = -1, dither_ = 0, dither_until_s_ = -1;
  // human: nerve (lateral acceleration it accepts), late and smoothed steering
  double nerve_mps2_ = 4, nerve_until_s_ = -1, hand_ = 0;
  double foot_ = 0;  // human: the throttle pedal, moved at a human rate
  std::vector<double> steer_memory_;  // reaction delay of the human
};

}  // namespace mppi::evidence
