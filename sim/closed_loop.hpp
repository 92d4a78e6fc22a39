#pragma once
// The closed loop: MPPI (any controller model of the library) drives a simulated car (any
// plant model) around a built-in track. The plant is integrated at 500 Hz behind rate-limited
// actuators, the controller runs at 50 Hz on the plant's exact state; laps are counted by
// progress along the centreline and a crash is a barrier contact or leaving the track (the
// car is then put back on the centreline at rest, and the run goes on; so is a car that stalls,
// making no progress along the track). Seeded, deterministic.
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dynamics/models/autorally_nn_model.hpp"
#include "dynamics/models/single_track_model.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi/backend_choice.hpp"
#include "mppi/controller_options.hpp"
#include "sim/plant.hpp"
#include "sim/step_observer.hpp"
#include "sim/summary.hpp"
#include "sim/track.hpp"

namespace mppi::sim {

struct ClosedLoopConfig {
  std::string track = "gazebo";           // gazebo | marietta | ccrf
  bool clockwise = false;                 // driving direction (default: counter-clockwise)
  // Controller model and simulated car: a registered model's name (mppi::model_names()) or
  // "corrected" (a corrected-model file of mppi-fit diagnose in model/plant_params_yaml).
  std::string model = models::AutoRallyNetworkModel::kName;
  std::string plant = models::SingleTrackModel::kName;
  double target_speed_mps = 6.0;          // v_x^d of the cost
  // A driver's speed schedule: (from time [s], v_x^d [m/s]) steps in ascending time; empty =
  // target_speed_mps throughout. At each step the running controller's cost changes
  // (Controller::set_cost_param); its warm-started plan is kept.
  std::vector<std::pair<double, double>> target_speed_schedule;
  int laps = 5;                           // stop after this many laps
  double max_time_s = 0.0;                // stop after this much simulated time; 0 = from laps
  // A car that makes less than stall_progress_m of progress along the centreline in
  // stall_timeout_s, while asked for at least 1 m/s with motion enabled, is stalled (spun and
  // stuck, or not moving): counted in RunSummary::stalls and put back like a crash. 0 = off.
  double stall_timeout_s = 10.0;
  double stall_progress_m = 2.0;
  ControllerOptions controller;           // K, T, seed, threads, noise, lambda, ...
  BackendChoice backend = BackendChoice::kCpu;  // rollout backend: cpu | vulkan | auto (factory/make_controller.hpp)
  BackendReport* backend_report = nullptr;  // if set, receives the backend that ran and why
  std::string cost_params_yaml;           // AutoRally cost weights; empty = data/config default
  std::string cost_map_npz;               // the controller's cost map; empty = the track's own
  std::string plant_params_yaml;          // plant's data file; empty = its default (data/config)
  std::string model_params_yaml;          // controller model's data file; empty = its default
  std::string network_npz;                // weights (npz) for learned models; empty = the shipped ones
  // Arithmetic of the controller's network hidden layers (models with set_precision: the
  // AutoRally network): "fp32" or "bf16" (falls back to fp32, with a note, without AVX512-BF16).
  std::string nn_precision = "fp32";
  // Grip and elevation by place (sim/surface_map.hpp, docs/SURFACES.md); empty = flat, grip 1.
  // Needs the single-track plant.
  std::string surface_yaml;
  ActuatorLimits actuators;               // plant actuator limits
  // How the limit lap that laps are measured against is computed (sim/limit_lap_methods.hpp):
  // "qss" (the quasi-steady-state lap on a racing line) or "collocation" (the minimum-time lap of
  // the single-track equations, laptime/; where it is registered).
  std::string limit_lap_method = "qss";
  // The actuator chain the controller plans through (sim/actuator_model.hpp): "none", "plant"
  // (the simulated car's own) or a corrected-model file; other than "none" it sets
  // controller.actuators.
  std::string actuator_model = "none";
  double plant_dt_s = 0.002;              // plant integration step (500 Hz)
  std::string out_dir;                    // log.csv, track.png, summary.json; empty = none
  bool progress = true;                   // print a line per lap to stderr
  // Fault drill: the backend fails like a lost GPU device after this many control steps
  // (Controller::inject_device_loss); the controller then goes on on its fallback (the CPU
  // backend for a GPU run) and the summary records the switch. -1 = never.
  long inject_device_loss_at_step = -1;
  bool through_chassis = true;            // controller -> chassis adapter (priorities, runstop,
                                          // watchdog, calibration) -> plant; false = direct
  StepObserver* observer = nullptr;       // sees every step, brings the operator's requests
};

// Runs the loop; throws mppi::Error for bad settings or data files. For a plant with
// single-track parameters (plant_vehicle_params) each lap is also given as a ratio to that
// vehicle's limit lap on the track (sim/limit_lap.hpp; RunSummary::limit_lap_s, lap_time_ratio):
// lap 1, which the car starts from rest at the start line, to the standing-start limit lap
// (RunSummary::standing_limit_lap_s), the others to the flying one.
RunSummary run_closed_loop(const ClosedLoopConfig& config);

// The single-track parameters of the config's plant, whose limit lap its laps are measured
// against: the single-track plant's file; the double-track's base; the full vehicle's base with
// its drag as aero_drag_kgpm (FullVehicleParams::rigid_limit); a corrected-model file with the
// single-track nominal: that car with its payload and grip (sim/corrected_limit_vehicle.hpp says
// which effects count). None for the other plants (the network, the kinematic bicycle, other
// corrected-model files). Throws mppi::Error for an unknown plant or a bad data file.
std::optional<SingleTrackParams> plant_vehicle_params(const ClosedLoopConfig& config);

}  // namespace mppi::sim
