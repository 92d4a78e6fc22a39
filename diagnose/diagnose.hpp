#pragma once
// `mppi-fit diagnose` as a library call: locate the mismatch between a recording and a nominal
// model, name the missing physics, write the corrected model, show the held-out fit before and
// after (report.json, report.md, report.html, residual_vs_regime.png, overlay.png, corrected_model.yaml).
#include <string>
#include <vector>

#include "diagnose/control_loss.hpp"
#include "diagnose/data.hpp"
#include "diagnose/fit.hpp"
#include "diagnose/locate.hpp"
#include "diagnose/unexplained.hpp"
#include "diagnose/model_comparison.hpp"
#include "diagnose/model_family.hpp"
#include "diagnose/replay.hpp"

namespace mppi::diagnose {

struct DiagnoseOptions {
  std::string holdout = "0.3";          // held-out fraction at the end, or a time range T0:T1 [s]
  std::string out_dir;                  // where the report goes; empty = no files
  double locate_horizon_s = 0.2;        // horizon of the locating residuals [s]
  std::vector<double> horizons_s = {0.2, 0.5, 1.0, 2.0};  // multi-step horizons reported [s]
  double headline_horizon_s = 1.0;      // the multi-step RMSE the summary quotes [s]
  SelectionOptions selection;
  // Rows of lost control (spins) are left out of the selection's fits and validation (not out of
  // the located mismatch, nor out of the held-out judgement): control_loss.hpp.
  ControlLossOptions control_loss;
  ReplayOptions replay;
  UnexplainedOptions unexplained;       // what of the remaining mismatch is reported unexplained
  bool plots = true;
  std::string params_source;            // nominal parameter file, for the report
  // Held-out recordings by name and time span (after concat): each gets its own before/after
  // line in the cross-recording table.
  struct Part {
    std::string name;
    double t0_s = 0, t1_s = 0;
  };
  std::vector<Part> heldout_recordings;
  // Data that neither the fit nor the validation (the held-out part, which also decides whether
  // a correction is written) sees: the correction the selection arrived at is scored on it
  // afterwards, written or not. nullptr = none. test_name names it in the report.
  const PreparedRecording* test = nullptr;
  std::string test_name;
};

struct DiagnoseResult {
  std::vector<Mismatch> mismatch;
  Selection selection;
  std::vector<HorizonMetrics> before, after;  // held out: one-step first, then options.horizons_s
  double headline_before = 0, headline_after = 0;  // normalised RMSE at the headline horizon
  double heldout_rmse_reduction = 0;          // 1 - after / before at the headline horizon
  std::size_t control_loss_rows = 0;          // training rows of lost control (left out of the selection where enough is left)
  // Share of the held-out squared error at the headline horizon that the correction removes,
  // per channel (1 - (RMSE after / before)^2), and where the rest sits (the corrected model's
  // residuals located on the held-out part, strongest first).
  double explained_share[kChannels] = {0, 0, 0};
  std::vector<Mismatch> remaining;
  // The corrected model's residuals located at UnexplainedOptions::long_horizon_s over all rows.
  std::vector<Mismatch> remaining_long;
  // Of those, what no named effect explains: clear and not a small remainder (unexplained.hpp).
  std::vector<Mismatch> unexplained;
  // Per held-out recording (DiagnoseOptions::heldout_recordings): normalised RMSE at the
  // headline horizon, nominal and corrected.
  struct PartScore {
    std::string name;
    double before = 0, after = 0;
  };
  std::vector<PartScore> per_recording;
  // On DiagnoseOptions::test (empty without one): the nominal and the selection's corrected model.
  ModelComparison test;
  std::string model_file;
  std::string json;                           // report.json text
};

// `nominal`: make_model_family(model, params file) (diagnose/model_family.hpp).
DiagnoseResult run_diagnosis(const PreparedRecording& d, const ModelFamily& nominal, const DiagnoseOptions& o);

}  // namespace mppi::diagnose
