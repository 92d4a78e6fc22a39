#pragma once
// Whether a recording can identify an effect: how much it excites the inputs and states an
// effect acts on (dynamics/effects.hpp's Excitation), and whether a fitted parameter ended at
// the end of its search range (then the data did not pin it down: the value is a bound, not an
// estimate).
#include <string>
#include <vector>

#include "diagnose/candidate_effects.hpp"
#include "diagnose/data.hpp"

namespace mppi::diagnose {

struct ExcitationLevels {
  double steer_std = 0;                 // of the steering command [1]
  double yaw_rate_std = 0;              // [rad/s]
  double throttle_std = 0;              // of the throttle command [1]
  double vx_std_mps = 0;                // [m/s]
  double speed_range_mps = 0;           // 95th - 5th percentile of vx [m/s]
  double lateral_accel_p95_mps2 = 0;    // 95th percentile of |vx r| [m/s^2]
  double longitudinal_accel_std_mps2 = 0;  // of dvx/dt over 0.1 s [m/s^2]
  bool speed_command = false;           // the recording declares its throttle column a speed command
};

// Levels over the rows in `mask` (empty = all usable rows).
ExcitationLevels measure_excitation(const PreparedRecording& d, const std::vector<char>& mask);

// Empty when the recording excites what `needs` asks for; otherwise why not, with the numbers.
std::string excitation_shortfall(Excitation needs, const ExcitationLevels& levels);

// Empty unless a fitted parameter of `spec` lies within `margin` (fraction of the search range)
// of an end of its search range that is not its default and not a closed end of its physical
// range (a share at 1 is an estimate); then which one and where.
std::string range_limit_shortfall(const EffectSpec& spec, const EffectParams& fitted, double margin = 0.01);
// The index into spec.params of the parameter range_limit_shortfall reports, or -1.
int range_limit_param(const EffectSpec& spec, const EffectParams& fitted, double margin = 0.01);

}  // namespace mppi::diagnose
