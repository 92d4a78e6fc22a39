#pragma once
// Values, not just syntax: a recording's channels are screened before diagnosis for
//   non-finite  NaN / inf in a column that has finite values elsewhere (an entirely empty
//               column is a recording without that channel, not a fault)
//   impossible  a magnitude no car or command reaches (|v| > 100 m/s, |yaw rate| > 100 rad/s,
//               |position| > 1e6 m, |command| > 10 where commands live in [-1, 1])
//   spike       a single-row outlier: the first differences into and out of the row are both
//               beyond `robust_z` robust standard deviations (1.4826 x median absolute deviation
//               of the column's first differences) and of opposite sign
//   jump        a velocity step no car makes (> max_accel_mps2 between two rows, yaw rate
//               > max_yaw_accel_radps2) where the position does not jump too (a respawn)
// Each flag names the row (0-based data row), the column and the value. The flagged rows and
// `guard_rows` on each side become unusable (prepare() in prepared_recording.hpp), so no fit segment
// contains them and the pieces around them are cut.
#include <cstddef>
#include <string>
#include <vector>

namespace mppi::sysid {

struct ScreenFlag {
  std::string file;      // the recording (its name in messages)
  std::size_t row = 0;   // 0-based data row of the recording
  double t_s = 0.0;      // its time stamp (NaN if the time itself is the bad value)
  std::string column;
  double value = 0.0;
  std::string kind;      // non-finite | impossible | spike | jump
};

struct ScreenOptions {
  double robust_z = 12.0;              // spike threshold in robust standard deviations
  double max_speed_mps = 100.0;
  double max_yaw_rate_radps = 100.0;
  double max_position_m = 1e6;
  double max_command = 10.0;
  double max_accel_mps2 = 200.0;       // about 20 g
  double max_yaw_accel_radps2 = 1000.0;
  int guard_rows = 1;                  // rows each side of a flagged row dropped with it
  // Cutting the recording into continuous pieces (prepare()):
  // - a gap of more than this many median sample intervals (a dropout, a seam);
  double max_gap_intervals = 3.0;
  // - a jump in position more than this multiple of what the car covers at its speed (+2 m/s);
  double max_jump_speed_multiple = 3.0;
  // - or a displacement that the measured velocities do not account for (a respawn, a teleport)
  //   by more than the larger of min_teleport_m (a 1:5 car's half length: less is position
  //   noise) and teleport_noise_multiple x the recording's median disagreement (a noisy or lagging
  //   position estimate must not cut everywhere).
  double min_teleport_m = 0.25;
  double teleport_noise_multiple = 10.0;
};

// One channel by name (x, y, yaw, vx, vy, yaw_rate, steer, throttle, roll, t) and its values.
struct ScreenColumn {
  std::string name;
  const std::vector<double>* values = nullptr;
};

// The flags of a recording's columns, ordered by row then column. `t` is the time column.
std::vector<ScreenFlag> screen_columns(const std::vector<double>& t, const std::vector<ScreenColumn>& columns,
                                       const ScreenOptions& options = {});

// Per row: 1 where a flag or the guard around one makes the row unusable.
std::vector<char> screened_rows(std::size_t rows, const std::vector<ScreenFlag>& flags, int guard_rows);

}  // namespace mppi::sysid
