#pragma once
// The concealed-effect sweep: per (hidden effect, size, seed) a synthetic recording (synth.hpp),
// the diagnosis with only the recording and the nominal model, and the judgement with what only
// the generator knows: the hidden effect ids, the truth model and the noise-free states.
#include <string>
#include <vector>

#include "diagnose/diagnose.hpp"
#include "diagnose/synth.hpp"

namespace mppi::diagnose {

// Held-out normalised multi-step RMSE at the headline horizon of one model, scored two ways.
struct ScoredRmse {
  double measured = 0;  // against the recording (sensor noise on the scored sample included)
  double clean = 0;     // against the noise-free states (the prediction error itself)
};

struct SweepRun {
  std::string truth = "none", size;  // hidden effect id ("none" = clean), "small" / "large" / "clean"
  int seed = 0;
  std::vector<std::string> truth_ids, named;
  bool right = false, wrong = false;                // a hidden / a non-hidden effect named
  bool right_family = false, wrong_family = false;  // a delay and a lag of one actuator = one family
  ScoredRmse before, after, truth_model;            // nominal, corrected, the hidden truth model
  std::vector<HorizonMetrics> before_h, after_h, truth_h;  // every horizon, scored against clean states

  double reduction_measured() const { return before.measured > 0 ? 1 - after.measured / before.measured : 0; }
  double reduction_clean() const { return before.clean > 0 ? 1 - after.clean / before.clean : 0; }
  // Share of the error the truth model removes that the corrected model removes too (clean).
  double removable_removed() const {
    const double removable = before.clean - truth_model.clean;
    return removable > 0 ? (before.clean - after.clean) / removable : 0;
  }
};

// Synthesises (unless `csv` exists: a rerun reuses recordings) and diagnoses one case.
// `so.work_dir` holds the truth model and the noise-free log; so.truth_ids names the effects.
SweepRun run_sweep_case(const SynthOptions& so, const std::string& csv, const DiagnoseOptions& o,
                        const std::string& truth_label, const std::string& size);

// One line of JSON per run (ids, selections and every horizon's metrics, three models).
std::string sweep_run_json(const SweepRun& r);

// The per-case table and the totals against the acceptance targets, in Markdown.
std::string sweep_summary_markdown(const std::vector<SweepRun>& runs);

}  // namespace mppi::diagnose
