#pragma once
// The independent evidence generator: the evidence car (car_physics.hpp) with hidden effects in
// their own forms (truth_effects.hpp, actuators.hpp), on a surface (grip patches, a hill),
// driven by a pursuit or human-like driver (drivers.hpp) round one of the three tracks in either
// direction, with crashes and respawns, sensor noise and glitches. It writes
//   FILE.csv        the recording (docs/RECORDING_FORMAT.md; commands sent at t, held to the
//                   next row: "command timing" of real recordings)
//   FILE.clean.csv  the same rows without noise and glitches (sensor faults kept: they are
//                   what the sensors show, not noise)
//   FILE.truth.json the effects, their sizes and forms, and the effect-table ids a diagnosis may
//                   name for each ("out of library" where none exists); the vehicle file whose
//                   constants the car has (`vehicle_params`: the nominal to diagnose against);
//                   for a place-dependent effect, the times the car was on each disc (`passes_s`)
// It shares no code with the diagnosis' candidate terms or their effect table (docs/EVIDENCE.md;
// a test checks its includes).
#include <cstdint>
#include <string>
#include <vector>

#include "evidence/truth_effects.hpp"

namespace mppi::evidence {

struct EvidenceNoise {
  double position_m = 0.03, yaw_rad = 0.008, vx_mps = 0.04, vy_mps = 0.04, yaw_rate_radps = 0.015;
  double scale = 1;               // x all of the above (0 = none)
  double glitch_rate = 0.002;     // per row: a one-row spike in one channel
  double drop_rate = 0.001;       // per row: the row is missing from the file
};

struct EvidenceOptions {
  TruthEffects truth;
  std::vector<std::string> truth_names;  // catalogue names (truth_effects.hpp)
  std::uint64_t seed = 1;
  double duration_s = 60;
  std::string track;       // gazebo | marietta | ccrf; empty = by seed
  std::string direction;   // ccw | cw; empty = by seed
  std::string driver;      // pursuit | human; empty = by seed
  double speed_min_mps = 3, speed_max_mps = 8;
  std::string vehicle_yaml;  // vehicle constants; empty = data/config/autorally_single_track.yaml
  EvidenceNoise noise;
  double physics_dt_s = 0.001, log_dt_s = 0.02;  // the driver acts and the log writes every log_dt_s
};

// The log (and driver) interval for a rate in Hz: a whole number of physics steps, between 5 and
// 500 Hz; throws mppi::Error otherwise.
double log_interval_s(double rate_hz, double physics_dt_s = 0.001);

// The times the car spent on a place-dependent effect (grip patches, a bump), per disc of it: one
// entry per pass, passes less than kPassGap_s apart merged. A place the car crossed once cannot be
// told from a change in time by the recording alone: no later pass over it confirms it.
struct PlacePasses {
  std::string effect;                                                  // catalogue name: grip_patches | bump
  std::vector<std::vector<std::pair<double, double>>> disc_passes_s;   // per disc: [enter, leave] of each pass [s]
  bool crossed_once() const {  // no disc passed twice (or never on it at all)
    for (const auto& d : disc_passes_s)
      if (d.size() >= 2) return false;
    return true;
  }
};
inline constexpr double kPassGap_s = 1.0;

struct EvidenceResult {
  std::string csv, clean_csv, truth_json, track, direction, driver;
  std::string vehicle_yaml;  // the vehicle constants read: the nominal a diagnosis should be given
  int crashes = 0, rows = 0;
  std::vector<PlacePasses> place_passes;  // one per place-dependent effect of the truth
};

// Throws mppi::Error for bad options or an unwritable path. Deterministic in the options.
EvidenceResult generate_evidence(const EvidenceOptions& o, const std::string& csv_path);

// FILE.csv -> FILE.clean.csv / FILE.truth.json
std::string clean_path_of(const std::string& csv_path);
std::string truth_path_of(const std::string& csv_path);

}  // namespace mppi::evidence
