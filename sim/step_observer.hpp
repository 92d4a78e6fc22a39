#pragma once
// A watcher of the closed loop (an operator page, a recorder): after every control step it sees
// the car, the controller and the chassis, and between steps it may hand back the operator's
// requests (pause, target speed, runstop, stop). It runs on the simulation thread, so an
// implementation must return quickly and never wait on a network.
#include <functional>
#include <optional>
#include <span>

#include "mppi/vehicle_state.hpp"

namespace mppi {
class Controller;
struct StepSummary;
namespace chassis {
class SimChassis;
}
}  // namespace mppi

namespace mppi::sim {

// Predicts the xy path of `count` control sequences from one model state: controls are
// T x nu x count (sample index fastest, as Controller::sampled_controls() lays them out),
// xy_out is count x (T + 1) x 2 (the start point first). count <= kChunk. Thread-safe: a copy
// of the controller's model, callable from any thread.
using PathPredictor = std::function<void(std::span<const float> model_state, std::span<const float> controls,
                                         int count, std::span<float> xy_out)>;

struct StepView {
  double t_s = 0.0;                      // simulated time after the step
  VehicleState state;                    // the car after the control period
  std::span<const float> model_state;    // the controller's start state of this step
  Control output;                        // the controller's output
  Control applied;                       // what the actuators hold now
  const StepSummary* summary = nullptr;
  const Controller* controller = nullptr;
  const chassis::SimChassis* chassis = nullptr;  // null when the loop bypasses the chassis
  int laps_completed = 0;
  int crashes = 0;
  double progress_m = 0.0;
  double target_speed_mps = 0.0;
  // A chassis known only by its state messages (over UDP): its runstop and watchdog flags.
  bool remote_chassis = false;
  bool remote_motion_enabled = false;
  bool remote_watchdog_tripped = true;
};

struct OperatorRequests {
  std::optional<double> target_speed_mps;  // new v_x^d for the cost
  std::optional<bool> motion_enabled;      // the operator's runstop: false stops the car
  bool stop = false;                       // end the run now
};

class StepObserver {
 public:
  virtual ~StepObserver() = default;
  // Once, before the first step: how to predict paths with the controller's model.
  virtual void on_start(PathPredictor predictor) = 0;
  virtual void after_step(const StepView& view) = 0;
  // Between steps: the operator's requests since the last call. May hold the simulation while
  // the operator has paused it (that is what pause means); must not wait on anything else.
  virtual OperatorRequests poll_requests(double t_s) = 0;
  virtual void on_finish() {}
};

}  // namespace mppi::sim
