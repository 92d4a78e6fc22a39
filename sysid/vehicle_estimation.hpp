#pragma once
// Vehicle parameter estimation from a recording: the vehicle models (sysid/vehicle_model_spec.hpp)
// as joint-state UKF / ALM-UKF process models, the estimation run (parameter convergence over
// time), and open-loop validation on held-out data. Used by `mppi-fit estimate`
// (docs/ESTIMATION.md).
#include <string>
#include <utility>
#include <vector>

#include "sysid/prepared_recording.hpp"
#include "sysid/alm_ukf.hpp"
#include "sysid/vehicle_model_spec.hpp"

namespace mppi::sysid {

struct EstimateSettings {
  bool adaptive = true;                  // ALM-UKF (else the standard joint-state UKF)
  UkfSettings ukf;
  double alm_window_s = 10.0;            // the paper: noise samples from the last 10 s
  bool alm_process = false;              // also re-estimate q, Q (see docs: Q with R drifts)
  bool alm_measurement = true;           // re-estimate r, R
  std::vector<std::string> measure;      // recording columns used (empty = all the model can use)
  std::vector<std::pair<std::string, double>> measurement_std;  // overrides of the defaults
  double param_initial_std = 0.3;        // log-scale: sd of log(p); linear: sd (abs) = this
  double param_walk_std_per_s = 0.003;   // random-walk sd per sqrt(s), same units (rescaled Q^p)
  double process_noise_scale = 1.0;      // multiplies the model's per-state process noise
  double t_begin_s = -1e300;             // fit on rows with t in [t_begin_s, t_end_s)
  double t_end_s = 1e300;
  int record_every = 5;                  // keep every n-th step in the history (plots, CSV)

  bool is_valid(std::string* why) const;
};

struct EstimateResult {
  std::vector<std::string> names;
  std::vector<double> initial, final_values, final_std;  // physical units (std: delta method)
  std::vector<double> t;                                 // history times
  std::vector<std::vector<double>> history;              // [k][param]
  std::vector<std::vector<double>> history_std;
  std::vector<std::string> measured;                     // columns used
  std::vector<double> innovation_rms;                    // per measured column, over the fit
  std::vector<double> measurement_std;                   // final sqrt(diag R) (ALM: estimated)
  int steps = 0;
  int projections = 0;
  int rejected_steps = 0;  // steps undone because the state went non-finite
  double wall_s = 0;
};

// Runs the joint-state filter over the fit rows. Throws mppi::Error for a recording that
// lacks a required column, or has too few rows.
EstimateResult estimate_parameters(const VehicleModelSpec& spec, const PreparedRecording& rec,
                                   const EstimateSettings& settings,
                                   const std::vector<double>& initial_values = {});

// Convergence time (the paper's "converges within 20 s"): the history time after which the
// parameter's estimate stays within `band` (relative, e.g. 0.05) of `reference`, i.e. the
// time of the first sample after its last exit from the band; t of the first sample if it is
// always inside; +infinity if the last sample is outside (never converged to the reference).
double convergence_time_to(const EstimateResult& r, std::size_t param, double band, double reference);
// The same around the parameter's own final estimate (always finite): when it settles.
double convergence_time(const EstimateResult& r, std::size_t param, double band);

struct ValidationResult {
  std::vector<std::string> channels;     // x, y, yaw, vx, vy, yaw_rate
  std::vector<double> open_loop_rms;     // whole segment open loop from its first state
  std::vector<double> horizon_rms;       // rollouts of horizon_s restarted every horizon_s
  std::vector<double> t;                 // open-loop trajectory (for plots)
  std::vector<std::vector<double>> simulated;  // [channel][k]
  std::vector<std::vector<double>> measured;   // [channel][k]
};

// Simulates the model with `values` over rows [begin, end) of `rec` with the recorded
// controls, open loop from the measured state of the first row, and in horizon_s chunks.
ValidationResult validate_parameters(const VehicleModelSpec& spec, const std::vector<double>& values,
                                     const PreparedRecording& rec, std::size_t begin, std::size_t end,
                                     double horizon_s = 1.0);

}  // namespace mppi::sysid
