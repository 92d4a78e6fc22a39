#pragma once
// The vehicle models prepared for estimation and calibration: which recording columns measure
// which state, the parameters that may be estimated, and a double-precision step with chosen
// parameter values (single-track with its actuators: sysid/single_track_spec.cpp; double-track and
// full vehicle: sysid/four_wheel_specs.cpp).
#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "dynamics/vehicle_params.hpp"
#include "sysid/prepared_recording.hpp"

namespace mppi::sysid {

// A vehicle model prepared for estimation: states, which recording columns measure which
// state, the parameters that may be estimated (YAML key names, e.g. "mass_kg", "tyre.B",
// "front_damper_Nspm"), and a double-precision step with chosen parameter values.
struct VehicleModelSpec {
  std::string kind;                       // single-track | double-track | full-vehicle
  int nx = 0;
  std::vector<std::string> state_names;
  std::vector<std::pair<std::string, int>> measurable;  // recording column -> state index
  std::vector<std::string> estimated;     // parameter names, in the order of the values
  std::vector<double> nominal;            // their values in the base parameters
  std::vector<bool> log_scale;            // estimated as log(value) (positive parameters)
  double max_substep_s = 0.002;           // integration step inside one sample interval
  // x <- x after dt with the estimated parameters set to `values` (others from the base).
  std::function<void(const std::vector<double>& values, double* x, const double* u, double dt)> step;
  // A full state from a recording row (unmeasured states from the measured ones).
  std::function<void(const PreparedRecording& rec, std::size_t row, double* x)> init_state;
  // Optional, after init_state: states that depend on the parameters and the command history
  // before `row` (the single-track's actuator lags, run over the preceding commands).
  std::function<void(const std::vector<double>& values, const PreparedRecording& rec, std::size_t row, double* x)>
      prime;
  // The base parameters with `values` set, as a YAML file the simulator/controller loads.
  std::function<std::string(const std::vector<double>& values)> to_yaml;
  // Per-state process-noise standard deviation per second (scaled by sqrt(dt)).
  std::vector<double> process_std_per_sqrt_s;
};

// The parameter names each model accepts (for --help and error messages).
std::vector<std::string> single_track_param_names();
std::vector<std::string> full_vehicle_param_names();
std::vector<std::string> double_track_param_names();

// Throws mppi::Error naming an unknown parameter and listing the known ones.
// keep_wheelbase: estimating cg_to_front_axle_m moves the CG (l_r = wheelbase - l_f).
VehicleModelSpec single_track_spec(const SingleTrackParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase = false);
VehicleModelSpec double_track_spec(const DoubleTrackParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase = false);
VehicleModelSpec full_vehicle_spec(const FullVehicleParams& base, const std::vector<std::string>& estimated,
                                   bool keep_wheelbase = false);

}  // namespace mppi::sysid
