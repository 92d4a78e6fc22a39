#pragma once
// The AutoRally paper's estimation protocol, in simulation: a scripted driver takes the
// full-vehicle plant (known parameters) through the paper's five manoeuvres on open ground,
//   1 low speed (4-6 m/s), 2 zig-zag (4-6 m/s), 3 straight acceleration and braking,
//   4 sliding, 5 high speed (up to 10 m/s),
// 20 s of each (100 s of training data), then a held-out 13 s lap-like segment (the paper's
// validation lap: straights and 180-degree turns at ~6 m/s), continuous in time and state.
// Layout (ProtocolLayout): by default the manoeuvres are interleaved as a human driver mixes
// them, a cycle of five 4 s pieces (one of each, in the order above) repeated five times, so
// every parameter is excited within the first 20 s; `sequential` drives each manoeuvre for
// its whole 20 s in turn (the tyre limit is then only reached at 60 s). A manoeuvre's pattern
// runs on its own clock (the time spent in that manoeuvre so far) in both layouts.
// Measurements get white Gaussian sensor noise; the commands are exact. The plant integrates
// at plant_dt_s with the commands held between samples and no actuator slew limit, so that
// FullVehicle::step_double(k, x, u, plant_dt_s) repeated reproduces it exactly (up to float).
#include <cstdint>
#include <string>
#include <vector>

#include "dynamics/vehicle_params.hpp"
#include "sim/recording.hpp"

namespace mppi::sysid {

enum class ProtocolLayout {
  interleaved,  // cycles of five pieces of piece_duration_s, one per manoeuvre (default)
  sequential,   // each manoeuvre for its whole manoeuvre_duration_s in turn
};

struct ProtocolOptions {
  double manoeuvre_duration_s = 20.0;   // total time in each of the five manoeuvres (5 x 20 = 100 s training)
  ProtocolLayout layout = ProtocolLayout::interleaved;  // see above
  double piece_duration_s = 4.0;        // interleaved: one manoeuvre piece (cycle = 5 pieces)
  double validation_duration_s = 13.0;  // the held-out lap-like segment
  double sample_rate_hz = 50.0;         // recording and command rate
  double plant_dt_s = 0.002;            // plant integration step (divides 1 / sample_rate_hz)
  std::uint64_t seed = 1;               // sensor-noise seed
  // Sensor noise standard deviations (RTK GPS, IMU, state estimator class values).
  double position_noise_m = 0.02;       // x, y
  double yaw_noise_rad = 0.01;          // yaw
  double velocity_noise_mps = 0.05;     // vx, vy, vz
  double rate_noise_radps = 0.01;       // yaw rate, roll rate, pitch rate
  double angle_noise_rad = 0.005;       // roll, pitch
  double accel_noise_mps2 = 0.1;        // ax, ay
  double wheel_noise_radps = 0.5;       // each wheel speed (~0.05 m/s at the rim)

  bool is_valid(std::string* why) const;
};

// Names of the five manoeuvres in order, then "validation".
const std::vector<std::string>& protocol_segment_names();

// "interleaved" | "sequential"; parse_protocol_layout throws mppi::Error for another name.
std::string protocol_layout_name(ProtocolLayout layout);
ProtocolLayout parse_protocol_layout(const std::string& name);

// The manoeuvre (1-5) driven at training time t_s and the time spent in that manoeuvre
// before t_s (its pattern clock). The last interleaved cycle is cut short where
// manoeuvre_duration_s is not a multiple of piece_duration_s.
struct ProtocolSegmentTime {
  int segment = 1;
  double manoeuvre_time_s = 0;
};
ProtocolSegmentTime protocol_segment_at(const ProtocolOptions& options, double t_s);

struct ProtocolRun {
  // Measured (noisy) recordings in the project format. Columns: the required ones, then
  // roll, pitch, roll_rate, pitch_rate, vz, ax, ay, wheel_speed (mean rim speed, m/s),
  // omega_lf, omega_rf, omega_lr, omega_rr [rad/s], segment (1-5 manoeuvre, 6 validation).
  sim::Recording training;    // t in [0, 5 x manoeuvre_duration_s), either layout
  sim::Recording validation;  // the following validation_duration_s
  // Noise-free truth at the same times: t, the 16 FullVehicle states (x, y, yaw, vx, vy,
  // yaw_rate, roll, omega_lf ... omega_rr, pitch, heave, roll_rate, pitch_rate, heave_rate),
  // steer, throttle, ax, ay, segment.
  sim::Recording truth;
};

// Runs the protocol. Throws mppi::Error for invalid options or parameters.
ProtocolRun run_protocol(const FullVehicleParams& truth_params, const ProtocolOptions& options = {});

// Writes dir/train.csv, dir/validation.csv, dir/truth.csv and dir/truth.yaml (the plant's
// parameters, loadable by load_full_vehicle_params). Creates dir.
void write_protocol(const ProtocolRun& run, const FullVehicleParams& truth_params,
                    const std::string& dir);

}  // namespace mppi::sysid
