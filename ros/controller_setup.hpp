#pragma once
// The controller node's settings and its controller, without ROS: the parameter names are
// AutoRally's path-integral launch file's where they mean the same (hz, num_timesteps,
// desired_speed, map_path, steering_std, throttle_std, gamma, lambda, max_throttle), plus the
// library's own (model, backend, variant, num_rollouts, seed). A ROS 1 node reads them from
// its private parameters; a ROS 2 node would read the same names.
// This header is C++17: ROS 1's message headers do not compile as C++20 (std::allocator<void>
// lost its rebind), so the nodes are C++17 and reach the library through this facade.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mppi/vehicle_state.hpp"

namespace mppi {
struct ControllerOptions;
}

namespace mppi::ros {

struct ControllerNodeSettings {
  double hz = 50.0;                 // control rate [Hz]; the model step is 1 / hz
  int num_timesteps = 100;          // T
  int num_rollouts = 1920;          // K
  double desired_speed = 6.0;       // target speed of the cost [m/s]
  std::string track = "gazebo";     // built-in track whose cost map is used when map_path is empty
  std::string map_path;             // cost map (.npz, AutoRally's track_boundaries format)
  std::string cost_params;          // AutoRally cost weights (YAML); empty = data/config default
  double steering_std = 0.275;      // sampling noise
  double throttle_std = 0.3;
  double gamma = 0.0;               // control-cost weight
  double lambda = 6.0;              // temperature
  double max_throttle = 0.65;
  double max_steering = 0.99;
  std::string model = "autorally-nn";  // a registered model (mppi::model_names())
  std::string model_params;         // its data file; empty = the model's default
  std::string backend = "cpu";      // cpu | vulkan | auto
  std::string variant = "plain";    // plain | tube | robust
  // robust: RMPPI's augmented sampling, with the real system's cost bounded (CPU backend)
  bool robust_augmented = false;
  double robust_cost_bound = 5000.0;
  // Online grip adaptation (mppi/lateral_force_adaptation.hpp): the target speed and the
  // throttle's limit follow the grip fitted from the measured motion (CPU backend).
  bool adapt_grip = false;
  int num_threads = 0;              // CPU threads; 0 = OpenMP default
  std::uint64_t seed = 1;
  // The operator page (docs/OCS.md) on http://127.0.0.1:serve_port/ (0 = any free port, its URL
  // with the page's token printed); -1 = none. Only in a build with the page (ocs/).
  int serve_port = -1;

  // Checks ranges and names; on failure writes which parameter and why.
  bool is_valid(std::string* why) const;
  ControllerOptions options() const;  // the MPPI options these settings give
};

// The controller built from the settings, stepping on the common state.
class NodeController {
 public:
  // Throws mppi::Error naming the parameter or file at fault.
  explicit NodeController(const ControllerNodeSettings& settings);
  ~NodeController();
  NodeController(const NodeController&) = delete;
  NodeController& operator=(const NodeController&) = delete;

  struct Step {
    bool ok = false;         // false: the output is the safe control and `reason` says why
    std::string reason;
    Control output;
    double optimizer_ms = 0.0;
  };
  // One step on the measured state at node time t_s; `applied` and `motion_enabled` (the
  // chassis' actuators and runstop, as it reports them) are shown on the operator page.
  Step step(const VehicleState& state, double t_s = 0.0, Control applied = {}, bool motion_enabled = true);
  // The operator page's runstop: false once its RUNSTOP was pressed (until released); true
  // without a page.
  bool page_motion_allowed() const;

  // The plan's path from the last state stepped on: (T + 1) x (x, y), row-major.
  void planned_path(std::vector<float>* xy) const;
  // Tube / robust variants: the last step's feedback gains, T x nu x nx row-major; else empty.
  const std::vector<float>& feedback_gains() const;
  int horizon() const;
  int controls() const;
  int model_states() const;
  const std::string& backend() const;  // the backend that runs, and why

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mppi::ros
