#pragma once
// The summary of one closed-loop run, written as JSON next to the run's recording and plot.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace mppi::sim {

// The controller left a failed backend for its fallback (a lost GPU -> the CPU backend).
struct BackendSwitchRecord {
  long control_step = 0;  // 0-based index of the control step that failed
  double time_s = 0.0;    // simulated time of that step
  std::string from, to;   // backend names
  std::string reason;     // the failure
};

struct RunSummary {
  std::string track;                  // "gazebo", ...
  std::string model;                  // the controller's dynamics model
  std::string plant;                  // the simulated car's model
  std::uint64_t seed = 0;
  int samples = 0;                    // MPPI rollouts per step
  int horizon = 0;                    // MPPI time steps
  double target_speed_mps = 0.0;
  double sim_time_s = 0.0;
  bool finished = false;              // reached the requested laps / time without stopping early
  int laps_completed = 0;
  std::vector<double> lap_times_s;
  // The limit lap of the plant's vehicle file on this track (sim/limit_lap.hpp): the flying lap and
  // the lap from a standing start at the start line (where the car is spawned at rest); each lap's
  // time over its reference: lap 1 over the standing-start lap, the others over the flying one.
  // NaN and empty for plants without single-track parameters (a NaN ratio where one is missing).
  double limit_lap_s = std::numeric_limits<double>::quiet_NaN();
  double standing_limit_lap_s = std::numeric_limits<double>::quiet_NaN();
  std::string limit_lap_method;  // sim/limit_lap_methods.hpp; empty where there is no limit lap
  std::vector<double> lap_time_ratio;
  int crashes = 0;
  std::vector<std::string> crash_reasons;
  // Stalls: the car made less than ClosedLoopConfig::stall_progress_m of progress along the track
  // in stall_timeout_s while asked to drive (spun and stuck, or not moving): put back like a crash.
  int stalls = 0;
  std::vector<double> stall_times_s;  // simulated time of each
  double mean_speed_mps = 0.0;
  double max_speed_mps = 0.0;
  // Body slip angle atan2(v_y, v_x) and lateral acceleration dv_y/dt + v_x r, at the control
  // rate; peaks over samples with v_x > 1 m/s (slip is undefined near standstill).
  double peak_slip_angle_rad = 0.0;   // max |slip|
  double p95_slip_angle_rad = 0.0;    // 95th percentile of |slip|
  double peak_lateral_accel_mps2 = 0.0;
  // Mean |u_k - u_{k-1}| of the commands sent to the car (log.csv's steer and throttle) over
  // consecutive control steps (sim/command_steps.hpp): how much the controller chatters.
  double mean_abs_steer_step = 0.0;
  double mean_abs_throttle_step = 0.0;
  double optimizer_ms_p50 = 0.0;      // wall time of one controller step, median
  double optimizer_ms_p99 = 0.0;
  double effective_sample_size_mean = 0.0;
  // The controller's variant: its sampler (mppi/sampler.hpp), the adaptive temperature's target
  // share of K (0 = fixed lambda) with the share of steps whose ESS was within +-25 % of it (NaN
  // when fixed) and the median temperature, and the actuator chain it planned through.
  std::string sampler = "gaussian";
  double ess_target_share = 0.0;
  double ess_in_band_share = std::numeric_limits<double>::quiet_NaN();
  double lambda_p50 = 0.0;
  std::string actuator_model = "none";
  // The variant (plain | tube | robust) and, for tube / robust, the steps whose nominal state
  // was put back on the measured one.
  std::string variant = "plain";
  int nominal_resets = 0;
  // Online adaptation of the model's lateral force (mppi/lateral_force_adaptation.hpp): on or
  // off, the scale at the end of the run and its median over the steps (1 when off).
  bool lateral_force_adaptation = false;
  double lateral_force_scale_final = 1.0;
  double lateral_force_scale_p50 = 1.0;
  std::string backend;                // the backend the run started on ("cpu", "vulkan")
  int failed_steps = 0;               // control steps that returned the safe control
  std::vector<BackendSwitchRecord> backend_switches;
};

// Pretty-printed JSON object with one key per field above (same names). NaN / inf -> null.
std::string to_json(const RunSummary& summary);
// Writes to_json() to `path`. Throws mppi::Error if the file cannot be written.
void write_summary(const std::string& path, const RunSummary& summary);

// The p-th percentile (p in [0, 100]) with linear interpolation between order statistics,
// like numpy.percentile's default: rank = p / 100 * (n - 1). NaN for an empty vector.
// Throws mppi::Error if p is outside [0, 100] or NaN.
double percentile(std::vector<double> values, double p);

}  // namespace mppi::sim
