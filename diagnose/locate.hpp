#pragma once
// Locating the mismatch: residuals of short open-loop predictions (measured - predicted change
// over a horizon, divided by it: an acceleration error) per channel, binned by driving regime,
// and split in time by change detection; each finding with its size and a z-score.
#include <string>
#include <vector>

#include "diagnose/data.hpp"
#include "diagnose/replay.hpp"

namespace mppi::diagnose {

// Residual series: per row k (start of a prediction), the error of the prediction made at k
// over horizon h: (measured(k + h) - predicted(k + h)) / h, per channel; NaN where unusable.
struct ResidualSeries {
  double horizon_s = 0.2;
  std::vector<double> e[kChannels];
};
ResidualSeries residual_series(const ReplayModel& model, const PreparedRecording& d, double horizon_s,
                               const ReplayOptions& o = {});

// The regime variables, per row.
inline constexpr int kRegimes = 6;
inline const char* const kRegimeNames[kRegimes] = {"speed", "lateral_accel", "longitudinal_accel",
                                                    "steer", "throttle", "steer_rate"};
inline const char* const kRegimeUnits[kRegimes] = {"m/s", "m/s^2", "m/s^2", "1", "1", "1/s"};
std::vector<double> regime_variable(const PreparedRecording& d, int regime);

struct BinStat {
  double lo = 0, hi = 0;    // regime range of the bin
  int n = 0;                // samples
  double mean = 0, rms = 0; // residual mean and rms
  double z = 0;             // mean / standard error (with correlation-corrected sample count)
};
// Residual of one channel in `bins` quantile bins of a regime variable (rows in mask).
std::vector<BinStat> bin_residual(const std::vector<double>& resid, const std::vector<double>& regime,
                                  const std::vector<char>& mask, int bins, double samples_per_independent);

struct Mismatch {
  std::string channel;      // vx, vy, yaw_rate
  std::string where;        // "speed in [6.1, 8.0] m/s", "t in [30.2, 45.0] s", "overall"
  double magnitude = 0;     // mean residual there [channel unit / s]
  double rms = 0;           // rms residual there
  double z = 0;             // how sure: mean / standard error
  std::string unit;
};
struct LocateOptions {
  double min_z = 4.0;  // a finding's mean residual, in standard errors (correlation counted)
  int bins = 4;        // quantile bins per regime variable
  // A place cell is judged only with this many rows in it: a cell the car crossed once or twice
  // (a second at 50 Hz) holds one stretch of correlated residual, not a property of the place.
  int min_cell_rows = 50;
  // A regime bin or place stands out only where its mean residual is also this share of the
  // channel's overall RMS: on a long recording a tiny, physically meaningless bias is
  // "significant", and a finding should be one worth modelling.
  double min_share_of_rms = 0.25;
};

// Findings sorted by |z|, strongest first: per channel the overall bias, the regime bins whose
// mean residual stands out, and time windows from binary-segmentation change detection.
std::vector<Mismatch> locate(const PreparedRecording& d, const ResidualSeries& res, const std::vector<char>& mask,
                             const LocateOptions& options = {});

}  // namespace mppi::diagnose
