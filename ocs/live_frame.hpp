#pragma once
// What the operator page shows of one control step, captured on the simulation (or control)
// thread into preallocated buffers: the car, the controller's summary, the chassis status and
// a sample of the sampled control sequences with their weights (lane 0 = the plan).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "base/batch.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {
class Controller;
}

namespace mppi::ocs {

// Paths drawn per frame: the plan and kChunk - 1 sampled rollouts (one batch of the model).
inline constexpr int kPathsPerFrame = kChunk;

// A commander the chassis does not report (a remote chassis' state message carries none).
inline constexpr int kCommanderNotReported = -100;

struct ChassisStatus {
  bool present = false;          // false: the loop has no chassis between controller and car
  bool motion_enabled = false;   // runstop state: true = autonomous motion allowed
  bool watchdog_tripped = true;
  int steering_commander = -3;   // Arbiter commander indices (chassis/arbiter.hpp)
  int throttle_commander = -3;
  int front_brake_commander = -3;
  long commands_accepted = 0;
  long runstops_accepted = 0;
};

struct LiveFrame {
  std::uint64_t step = 0;
  double t_s = 0.0;
  VehicleState state;
  Control output, applied;
  float optimizer_ms = 0.f;
  float effective_sample_size = 0.f;
  int valid_samples = 0;
  int num_samples = 0;
  int laps_completed = 0;
  int crashes = 0;
  double progress_m = 0.0;
  double target_speed_mps = 0.0;
  ChassisStatus chassis;
  // Paths: `paths` control sequences, horizon x nu x paths (lane fastest); weights[0] is the
  // plan's (NaN), the others the sampled rollouts' normalised weights.
  int horizon = 0, nu = 0, paths = 0;
  std::vector<float> model_state;
  std::vector<float> controls;
  std::vector<float> weights;

  // Sizes the buffers once, so that capture allocates nothing.
  void reserve(int num_states, int num_controls, int horizon_steps);
};

// Picks kPathsPerFrame - 1 samples of the last iteration: the best-weighted one and the rest
// spread evenly over the sample index; writes their indices (ascending, distinct when K allows)
// to `indices` and returns how many. K < 1 or no weights: 0.
int pick_rollouts(std::span<const float> weights, std::span<int> indices);

// Copies the plan (lane 0: `first_control` then the shifted nominal) and the picked rollouts
// with their weights from the controller into the frame. No allocation once reserved. The
// controller must not be stepping meanwhile (call it right after step() on its thread).
void capture_paths(const Controller& controller, std::span<const float> first_control, LiveFrame& frame);

}  // namespace mppi::ocs
