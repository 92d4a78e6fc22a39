#pragma once
// Synthetic recordings from a dynamics model driven open loop through the AutoRally paper's
// five estimation manoeuvres (low speed 4-6 m/s, zig-zag, straight acceleration and braking,
// sliding, high speed up to 10 m/s), interleaved in pieces, with randomised amplitudes and
// periods and a little coloured command noise so that every recording (seed) is different.
// Used to treat a learned model (the AutoRally network) as the recording of a real car, and
// for oracle tests (a plant with known parameters). The scripted driver closes a loop only on
// the speed (a throttle feed-forward plus proportional term) and, in the straight-line pieces,
// on the yaw rate; the commands it gave are what the recording holds.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sim/recording.hpp"

namespace mppi::sysid {

struct ManoeuvreOptions {
  double duration_s = 100.0;      // recording length
  double piece_duration_s = 4.0;  // one manoeuvre piece; the five manoeuvres cycle
  double sample_dt_s = 0.02;      // command and sample interval (AutoRally's 50 Hz)
  std::uint64_t seed = 1;         // amplitudes, periods, noise
  double min_throttle = -0.99;    // AutoRally's command limits
  double max_throttle = 0.65;
  // Throttle that holds speed v on the flat: ff_offset + ff_per_mps v (the AutoRally
  // network holds 6.7 m/s at 0.30 and 1.7 m/s at 0.20).
  double ff_offset = 0.19;
  double ff_per_mps = 0.018;
  double speed_gain_per_mps = 0.15;  // proportional speed feedback [throttle per m/s]
  double initial_speed_mps = 5.0;
  // The driver recovers (countersteers, holds 5 m/s) whenever |yaw rate|, |v_y| or v_x leave
  // these bounds, so the sequences stay where the paper's data were taken.
  double recover_yaw_rate_radps = 2.5;
  double recover_lateral_mps = 2.0;
  double recover_below_mps = 3.5;
  // White command noise added to every sample (std, normalised command units), as an MPPI
  // controller's applied commands carry its exploration noise when few samples dominate the
  // weights. 0 = none.
  double steer_dither_std = 0.0;
  double throttle_dither_std = 0.0;
  // Column names for the model's states after the common 7 (x[7], x[8], ...), recorded too
  // when given (e.g. "omega_front", "omega_rear" for the single-track's wheel speeds).
  std::vector<std::string> extra_state_columns;

  bool is_valid(std::string* why) const;
};

// x <- x after dt_s with controls u = {steer, throttle}; x holds the library's common state
// (x, y, yaw, vx, vy, yaw_rate, roll) first, then any model-specific states.
using RolloutStep = std::function<void(std::vector<double>& x, const double u[2], double dt_s)>;

// Drives `step` from x0 (its vx is replaced by options.initial_speed_mps, the rest kept) and
// returns a recording with the required columns plus roll and segment (manoeuvre 1-5).
// Throws mppi::Error for invalid options or a state that becomes non-finite.
sim::Recording roll_out_manoeuvres(const RolloutStep& step, std::vector<double> x0,
                                   const ManoeuvreOptions& options);

}  // namespace mppi::sysid
