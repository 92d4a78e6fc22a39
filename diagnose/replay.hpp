#pragma once
// Replay of the recorded commands through a model from recorded states: open-loop predictions
// over segments (one-step = 1 sample, multi-step = 0.2 / 0.5 / 1 / 2 s), and their metrics.
#include <array>
#include <vector>

#include "diagnose/data.hpp"
#include "diagnose/model_family.hpp"

namespace mppi::diagnose {

struct ReplayOptions {
  double substep_s = 0.002;  // integration step inside a sample interval [s] (the simulator's)
  double prime_s = 0.6;      // command history run through the actuator chains before a start [s]
  double wheel_prime_s = 0.5;  // of which the last part runs the full model (wheel speeds) [s]
  // Blend towards the measured velocities per sample there (1 = raw). 0.25 over 25 samples
  // averages the sensor noise of the start state down to about a third (sqrt(g / (2 - g))); a
  // start state as noisy as the sensor would put a floor under every multi-step error.
  double observer_gain = 0.25;
};

// Predicted vx, vy, yaw rate (and x, y) along a segment: out[(i - 1) * 5 + c] for i = 1..len,
// c = vx, vy, yaw_rate, x, y.
inline constexpr int kPredStride = 5;
void predict_segment(const ReplayModel& model, const PreparedRecording& d, const Segment& s,
                     const ReplayOptions& o, double* out);

// The same for every segment of `segs`, one after the other in `out` (segment n's predictions
// start at the sum of the earlier lengths x kPredStride). Segments of one length are replayed
// ReplayModel::kLanes at a time in SIMD (a lane with less command history before its start joins
// its group later), a group of fewer than kMinLockstepSegments one at a time. The lanes share each
// row's step: the mean of the intervals of the lanes within kSharedStepTolerance of their median;
// a lane whose interval differs more (a missing row) is stepped on its own for that row. So on a
// recording with timing jitter the predictions differ from predict_segment's by that jitter's
// effect; on a regular one, gaps included, they are the same.
inline constexpr std::size_t kMinLockstepSegments = 3;
inline constexpr double kSharedStepTolerance = 0.1;
void predict_segments(const ReplayModel& model, const PreparedRecording& d, const std::vector<Segment>& segs,
                      const ReplayOptions& o, double* out);

// Weighted residuals (prediction - measurement) / scale_c for every sample of every segment,
// channels vx, vy, yaw_rate; appended to `res` (resized).
void segment_residuals(const ReplayModel& model, const PreparedRecording& d,
                       const std::vector<Segment>& segs, const std::array<double, kChannels>& scale,
                       const ReplayOptions& o, std::vector<double>* res);

// Per channel standard deviation of the measured signal over rows in mask (floored).
std::array<double, kChannels> channel_scales(const PreparedRecording& d, const std::vector<char>& mask);

// Metrics of open-loop prediction at one horizon over starts in `mask` every `stride` rows.
struct HorizonMetrics {
  double horizon_s = 0;
  int starts = 0;
  std::array<double, kChannels> rmse{}, fit_percent{};
  double position_rmse_m = 0;
  double normalized_rmse = 0;  // sqrt(mean_c (rmse_c / std_c)^2), std of the measured channel
};
// `reference`, when given, is what predictions are scored against instead of d's own states:
// the noise-free states of a synthetic recording (same rows as d). Predictions still start from
// d's (noisy) states; sensor noise on the scored sample, which no model can predict, is left out.
std::vector<HorizonMetrics> horizon_metrics(const ReplayModel& model, const PreparedRecording& d,
                                            const std::vector<char>& mask,
                                            const std::vector<double>& horizons_s, int stride,
                                            const ReplayOptions& o, const PreparedRecording* reference = nullptr);

}  // namespace mppi::diagnose
