#pragma once
// The concealed-effect generator: a truth plant = nominal single-track + hidden effects
// (CorrectedSingleTrack), driven around a track in closed loop by MPPI that uses the NOMINAL
// model (sim::run_closed_loop), logged at 50 Hz with realistic sensor noise added. The
// diagnosis tool later gets only the recording and the nominal model.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dynamics/corrected_single_track.hpp"

namespace mppi::diagnose {

struct SensorNoise {
  double position_m = 0.02;     // x, y (GPS/mocap-grade state estimate)
  double yaw_rad = 0.005;
  double vx_mps = 0.05;
  double vy_mps = 0.03;
  double yaw_rate_radps = 0.02; // gyro
  double scale = 1.0;           // multiplies all of the above (0 = noise-free)
};

struct SynthOptions {
  EffectParams truth;                 // hidden effects (defaults = none)
  std::vector<std::string> truth_ids; // their ids, written to the metadata
  std::uint64_t seed = 1;             // MPPI and noise seed
  double duration_s = 60.0;           // recording length [s]
  double target_speed_mps = 8.0;
  std::string track = "gazebo";
  int samples = 256;                  // MPPI K (small: the generator runs many recordings)
  int horizon = 50;                   // MPPI T
  int threads = 0;
  SensorNoise noise;
  std::string work_dir;               // scratch folder (truth file, raw log); required
};

// Writes the recording to `csv_path`. Returns the number of crashes during the run.
int synthesize(const SynthOptions& o, const std::string& csv_path);

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
