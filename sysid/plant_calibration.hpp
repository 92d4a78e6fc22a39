#pragma once
// Calibrating a physics model to recordings by its multi-step open-loop prediction error:
// every `stride_s` a rollout of `horizon_s` starts from the recorded state and is driven by
// the recorded commands; the residuals are the predicted minus recorded channels (body
// velocities and yaw rate by default), each divided by the channel's standard deviation in
// the recording (normalised RMSE). The recording is the prepared one (sysid/prepared_recording.hpp)
// that the diagnosis also replays: its pieces say where a rollout may run, and its command timing
// which command acts over each sample interval. The fit is Levenberg-Marquardt with a forward-difference
// Jacobian over the parameters a VehicleModelSpec exposes (positive ones in log space), kept
// inside a box (base/least_squares.hpp). docs/CALIBRATION.md.
#include <string>
#include <utility>
#include <vector>

#include "sim/recording.hpp"
#include "sysid/manoeuvre_rollout.hpp"
#include "sysid/vehicle_estimation.hpp"

namespace mppi::sysid {

struct PredictionErrorOptions {
  double horizon_s = 1.0;   // rollout length
  double stride_s = 0.5;    // a rollout starts every stride_s
  std::vector<std::string> channels = {"vx", "vy", "yaw_rate"};
  std::vector<double> report_horizons_s = {0.1, 0.25, 0.5, 1.0};  // error tabulated at these

  bool is_valid(std::string* why) const;
};

struct PredictionError {
  std::vector<std::string> channels;
  std::vector<double> scales;                  // channel standard deviation (normaliser)
  std::vector<double> horizons_s;              // = options.report_horizons_s
  std::vector<std::vector<double>> nrmse_at;   // [channel][horizon]: RMSE at that lead / scale
  std::vector<double> nrmse;                   // [channel]: RMSE over every lead in (0, horizon] / scale
  double mean_nrmse = 0;                       // mean of nrmse over the channels (the headline)
  int rollouts = 0;
};

// Standard deviation of each column over the recording (finite values); throws mppi::Error
// for a missing column or one that is constant.
std::vector<double> channel_scales(const PreparedRecording& rec, const std::vector<std::string>& channels);

// Prediction error of the model with `values` on `rec`, normalised by `scales` (one per
// channel). Throws mppi::Error for a channel the model does not measure, invalid options, or
// a recording with no gap-free stretch of one horizon. Rollouts start every stride_s inside the
// recording's continuous pieces (make_segments): none spans a gap, a seam between joined
// recordings or a screened-out value. A rollout that goes non-finite counts with residual
// 10 (normalised) from then on.
PredictionError prediction_error(const VehicleModelSpec& spec, const std::vector<double>& values,
                                 const PreparedRecording& rec, const std::vector<double>& scales,
                                 const PredictionErrorOptions& options = {});

// Recordings joined end to end into one, for a fit or a judgement over several: the columns
// every piece has (in the first one's order), each later piece shifted in time to start
// `gap_s` after the previous one ends. prediction_error() starts no rollout across a gap, and
// a gap longer than 1 s keeps the actuator priming (1 s of command history) from reaching
// across it. prepare() the result before fitting to it. Throws mppi::Error for no pieces, a piece with fewer than 2 rows, pieces
// sampled at different intervals (more than 1 % apart), or gap_s <= 1.
sim::Recording join_recordings(const std::vector<sim::Recording>& pieces, double gap_s = 10.0);

// A recording of a learned model made elsewhere (e.g. an mppi-sim log with the network as the
// plant), to calibrate against: when it has applied_steer and applied_throttle columns (the
// commands the car received, after the simulator's actuator limits) they replace steer and
// throttle. Throws mppi::Error naming the file and the row for a missing or non-finite
// command, v_x, v_y or yaw rate (a calibration cannot roll out through it).
sim::Recording read_learned_model_log(const std::string& path);

// Channel `channel` of the state after `step` is driven from `x` with the constant command `u`,
// at each of `leads_s` (increasing).
std::vector<double> step_response(const RolloutStep& step, std::vector<double> x, const double u[2],
                                  std::size_t channel, const std::vector<double>& leads_s, double dt_s = 0.02);

// Yaw rate of the plant `spec` with `values` at each of `leads_s` (increasing) after a steering
// step from straight driving at speed_mps, the throttle held (its actuator states, if any,
// primed with 1 s of straight driving): how fast and how far the car answers a steering command.
std::vector<double> steering_step_yaw_rate(const VehicleModelSpec& spec, const std::vector<double>& values,
                                           double speed_mps, double steer, double throttle,
                                           const std::vector<double>& leads_s, double dt_s = 0.02);

struct CalibrationOptions {
  PredictionErrorOptions error;
  int max_iterations = 40;
  double relative_tolerance = 1e-5;  // stop when the cost falls less than this (relative)
  // Box, per parameter: positive (log-scale) ones within [nominal / range, nominal x range];
  // tyre.C in [0.05, 1.99], tyre.E in [-10, 0.99], rear_tyre_C_scale in [0.3, 1.6],
  // rear_tyre_B_scale and rear_tyre_D_scale in [0.3, 3], steer_lag_s and throttle_lag_s in
  // [0, 0.5] s, steer_cubic in [-0.9, 1.9], steer_offset in [-0.3, 0.3]; other linear ones
  // unbounded.
  double log_range = 20.0;
  std::vector<std::pair<double, double>> bounds;  // overrides (physical units), one per parameter

  bool is_valid(std::string* why) const;
};

struct CalibrationResult {
  std::vector<std::string> names;
  std::vector<double> initial, values;       // physical units
  std::vector<double> cost_history;          // mean squared normalised residual per iteration
  std::vector<bool> at_bound;                // value ended on its box edge
  int iterations = 0;
  int evaluations = 0;
};

// Fits spec's estimated parameters, starting from `initial` (default: spec.nominal), to
// minimise the mean squared normalised prediction residual on `rec` with `scales`. A lag
// (steer_lag_s, throttle_lag_s) that would start at 0, where it has no derivative, starts at 0.05 s.
CalibrationResult calibrate(const VehicleModelSpec& spec, const PreparedRecording& rec,
                            const std::vector<double>& scales, const CalibrationOptions& options = {},
                            std::vector<double> initial = {});

}  // namespace mppi::sysid
