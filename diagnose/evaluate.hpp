#pragma once
// `mppi-fit evaluate` as a library call: score a written corrected model (corrected_model.yaml)
// against its own nominal model on any recording, with the diagnosis' replay and metrics, so that
// yesterday's correction can be checked on today's run. A model and a recording that are not of
// the same car are refused, naming what differs.
#include <map>
#include <string>
#include <vector>

#include "diagnose/data.hpp"
#include "diagnose/model_comparison.hpp"
#include "diagnose/replay.hpp"
#include "dynamics/corrected_model.hpp"

namespace mppi::diagnose {

struct EvaluateOptions {
  // The rows scored: "all", a held-out fraction at the end ("0.3", as the diagnosis holds out by
  // default, which reproduces its held-out figures), or a time range "T0:T1" [s].
  std::string rows = "all";
  std::vector<double> horizons_s = {0.2, 0.5, 1.0, 2.0};  // multi-step horizons [s]
  double headline_horizon_s = 1.0;                         // the horizon the summary quotes [s]
  ReplayOptions replay;
  // Largest relative difference of the car's mass and wheelbase between the model and the
  // recording's metadata (`# mass_kg:`, `# wheelbase_m:`) that still counts as the same car.
  double geometry_tolerance = 0.1;
};

struct EvaluateResult : ModelComparison {
  std::size_t rows_scored = 0;
};

// Throws mppi::Error naming both values when the model and the recording are not of the same
// car: the vehicle the model was fitted on (its fitted_on section) against the recording's
// `# vehicle:`, the command the throttle column holds (throttle or speed), and the model's mass
// and wheelbase against the recording's metadata, where both sides give them.
void check_model_matches_recording(const CorrectedModelFile& model, const std::string& model_source,
                                   const PreparedRecording& d, const EvaluateOptions& o = {});

// The corrected model and its nominal model replayed on d's scored rows. Checks the match first.
EvaluateResult evaluate_corrected_model(const CorrectedModelFile& model, const std::string& model_source,
                                        const PreparedRecording& d, const EvaluateOptions& o = {});

// What the corrected-model file records of the recording a diagnosis fitted it on (its
// fitted_on section): the recording's source, vehicle and command kind, its sample interval.
std::map<std::string, std::string> fitted_on_of(const PreparedRecording& d);

}  // namespace mppi::diagnose
