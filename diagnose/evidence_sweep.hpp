#pragma once
// The diagnosis judged on the independent evidence generator (evidence/): per hidden effect
// (or pair, or none) and seed, a recording of that generator, the diagnosis with only the
// recording and the nominal model, and the judgement with the generator's truth file and
// noise-free states. The generator itself never sees this file's includes.
#include <string>
#include <vector>

#include "diagnose/diagnose.hpp"
#include "evidence/generator.hpp"

namespace mppi::diagnose {

struct EvidenceCase {
  std::vector<std::string> effects;  // catalogue names (empty = effect-free)
  std::string size;                  // small | large | pair | clean
  std::string assignments;           // key=value,... of TruthEffects
  int seed = 1;
  std::string label() const;         // e.g. "steer_delay_large_s3"
};

struct EvidenceRun {
  EvidenceCase c;
  std::string track, direction, driver;
  int crashes = 0;
  std::vector<std::string> named, suspected, acceptable;  // acceptable: ids of the truth effects
  std::vector<double> named_inclusion;  // per named effect: share of the stability resamples that chose it (-1: none)
  std::vector<std::string> partial;     // a partial correction (not named): a mismatch remains, or ambiguous
  std::string ambiguous;                // named effects and their substitutes (Selection::ambiguous)
  int unexplained = 0;                  // unexplained mismatches reported
  bool out_of_library = false;   // every hidden effect is outside the library
  // Place-dependent effects none of whose discs the car passed twice: no later pass can confirm
  // them (the recording alone cannot tell a patch from a change in time), so naming them is not
  // required; naming them is still right.
  std::vector<std::string> crossed_once;
  bool right = false;            // every in-library effect named by an acceptable id, those crossed once
                                 // excepted (out of library, or only effects crossed once: nothing wrong named)
  bool right_strict = false;     // every in-library effect named, those crossed once included
  bool wrong = false;            // an id named that no hidden effect accounts for
  double before_clean = 0, after_clean = 0;  // held-out normalised 1-s RMSE against the noise-free states
  double reduction() const { return before_clean > 0 ? 1 - after_clean / before_clean : 0; }
  bool corrected_worse() const { return after_clean > before_clean * 1.001; }
  std::string error;             // a run that failed (generator or diagnosis), not scored
};

struct EvidenceGrid {
  int seeds = 5;
  std::vector<std::string> sizes = {"small", "large"};
  std::vector<std::string> effects;  // empty = every catalogue effect in the grid (TruthEffectInfo::in_grid)
  int pairs = 8;                     // 2-effect combinations (large sizes), from a fixed list
  int clean = 20;                    // effect-free recordings
  double duration_s = 60;
  std::string vehicle_yaml;          // the car's constants and the diagnosis' nominal (empty: the generator's default)
  double rate_hz = 50;               // the driver's and the log's rate
};
// The reduced grid: 1 seed, both sizes, 3 pairs, 4 effect-free recordings.
EvidenceGrid reduced_evidence_grid();
std::vector<EvidenceCase> evidence_cases(const EvidenceGrid& g);

// Scores r->named against r->c's hidden effects: acceptable ids, right, right_strict, wrong and
// crossed_once (a place effect none of whose discs the car passed twice, `place_passes`).
void score_evidence_run(const std::vector<evidence::PlacePasses>& place_passes, EvidenceRun* r);

// Generates (unless the recording exists) and diagnoses one case against the vehicle file the
// car was built from; never throws (error set).
EvidenceRun run_evidence_case(const EvidenceCase& c, const std::string& dir, double duration_s,
                              const DiagnoseOptions& o, const std::string& vehicle_yaml = "", double rate_hz = 50);

std::string evidence_run_json(const EvidenceRun& r);
// The runs of a runs.jsonl (one evidence_run_json line each; a sweep cut short is summarised
// from what it finished). Throws mppi::Error naming the file and line for a malformed line.
std::vector<EvidenceRun> read_evidence_runs(const std::string& jsonl_path);
// The table (per effect and size) and the totals against the bars, in Markdown.
std::string evidence_summary_markdown(const std::vector<EvidenceRun>& runs);
std::string evidence_summary_json(const std::vector<EvidenceRun>& runs);

}  // namespace mppi::diagnose
