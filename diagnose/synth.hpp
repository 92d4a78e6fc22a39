#pragma once
// The concealed-effect generator: a truth plant = nominal single-track + hidden effects
// (WithEffects<SingleTrack>), driven around a track in closed loop by MPPI that uses the NOMINAL
// model (sim::run_closed_loop), logged at 50 Hz with realistic sensor noise added. The
// diagnosis tool later gets only the recording and the nominal model.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dynamics/corrected_model.hpp"
#include "dynamics/model_registry.hpp"
#include "sim/recording.hpp"

namespace mppi::diagnose {

struct SensorNoise {
  double position_m = 0.02;     // x, y (GPS/mocap-grade state estimate)
  double yaw_rad = 0.005;
  double vx_mps = 0.05;
  double vy_mps = 0.03;
  double yaw_rate_radps = 0.02; // gyro
  double roll_rad = 0.005;      // the optional roll column (drawn from its own stream)
  double scale = 1.0;           // multiplies all of the above (0 = noise-free)
};

struct SynthOptions {
  EffectParams truth;                 // hidden effects (defaults = none)
  // The truth's base model (library defaults), one of kCorrectedNominalModels. The driver
  // (MPPI) uses the same model without the effects.
  std::string nominal_model = mppi::models::SingleTrackModel::kName;
  std::vector<std::string> truth_ids; // their ids, written to the metadata
  std::uint64_t seed = 1;             // MPPI and noise seed
  double duration_s = 60.0;           // recording length [s]
  // The driver: as on a real track, the target speed changes over time (a new v_x^d drawn
  // uniformly in [speed_min_mps, speed_max_mps], held for hold_min_s..hold_max_s), so the
  // recording has accelerating, cruising and braking and the throttle is not pinned at its
  // limit. speed_min_mps == speed_max_mps (or vary_speed = false): constant target_speed_mps.
  bool vary_speed = true;
  double speed_min_mps = 3.0;
  double speed_max_mps = 8.0;
  double hold_min_s = 2.0;
  double hold_max_s = 6.0;
  double target_speed_mps = 8.0;      // the constant target when vary_speed is false
  std::string track = "gazebo";
  int samples = 256;                  // MPPI K (small: the generator runs many recordings)
  int horizon = 50;                   // MPPI T
  int threads = 0;
  SensorNoise noise;
  std::string work_dir;               // scratch folder (truth file, raw log); required
};

// The driver's speed schedule: (from time [s], target speed [m/s]) steps covering
// [0, duration_s), each speed uniform in [speed_min, speed_max], each held uniform in
// [hold_min_s, hold_max_s]. Deterministic in `seed`. Throws mppi::Error for bad ranges.
std::vector<std::pair<double, double>> speed_schedule(std::uint64_t seed, double duration_s, double speed_min_mps,
                                                      double speed_max_mps, double hold_min_s, double hold_max_s);

// Writes the recording to `csv_path`. Returns the number of crashes during the run.
int synthesize(const SynthOptions& o, const std::string& csv_path);

// A fast open-loop variant for tests: the truth plant (500 Hz, no slew limits) driven on open
// ground by random steering and throttle (held 0.1-0.5 s, speed kept in about 3-9 m/s), logged at
// 50 Hz with sensor noise, in the recording format (metadata source "mppi-fit synth").
// nominal_model: the truth's base, single-track, double-track,
// full-vehicle, kinematic, autorally-nn (WithEffects<Model>), with the library's defaults.
sim::Recording synthesize_open_loop(const EffectParams& truth, std::uint64_t seed, double duration_s,
                                    const SensorNoise& noise = {}, const std::string& nominal_model = mppi::models::SingleTrackModel::kName);

// Parses "key=value,key=value" (EffectParams field names, as in the corrected-model file) into
// `e`; returns the effect ids the keys belong to. Throws mppi::Error for an unknown key.
std::vector<std::string> parse_effect_assignments(const std::string& text, EffectParams* e);

// The sweep's truth cases: per effect id, (small, large) sizes as key=value text.
struct SweepCase {
  std::string id;
  std::string small, large;
};
const std::vector<SweepCase>& sweep_cases();

}  // namespace mppi::diagnose
