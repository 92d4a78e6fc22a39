#pragma once
// Naming the missing physics: nonlinear least squares fits of candidate effects (Levenberg-
// Marquardt with parameter uncertainties from the Jacobian; time-like parameters by grid
// search) on multi-step open-loop residuals, and greedy forward selection judged on
// validation segments with the BIC, so that an effect that does not help is not named.
#include <array>
#include <string>
#include <vector>

#include "sysid/diagnose/data.hpp"
#include "sysid/diagnose/effects.hpp"
#include "sysid/diagnose/model_family.hpp"
#include "sysid/diagnose/replay.hpp"

namespace mppi::diagnose {

// The data a fit works on: segments and channel scales.
struct FitProblem {
  const DiagData* data = nullptr;
  const ModelFamily* family = nullptr;  // the nominal model; members = nominal + effects
  std::vector<Segment> segments;
  std::array<double, kChannels> scale{};
  ReplayOptions replay;
};

// Mean squared weighted residual of a model on a problem.
double mean_cost(const FitProblem& p, const EffectParams& e);

struct ParamEstimate {
  std::string name, unit;
  double value = 0, stddev = 0;
};

struct FitResult {
  std::vector<ParamEstimate> params;
  EffectParams effects;      // base + fitted values
  double cost = 0;           // mean squared weighted residual at the optimum
  int iterations = 0;
};

// Fits the free parameters `free` starting from `base` (whose other fields stay fixed).
FitResult fit_params(const FitProblem& p, const EffectParams& base, const std::vector<ParamSpec>& free,
                     int max_iterations = 15);

// One effect (spec) on top of base: start-value grid search, then LM.
FitResult fit_effect(const FitProblem& p, const EffectParams& base, const EffectSpec& spec);

struct SelectionOptions {
  double fit_horizon_s = 0.5;       // multi-step horizon of the fit residuals [s]
  // Relative validation-cost reduction an effect must give. The cost includes sensor noise, so
  // a barely visible effect moves it by a few %; 3 % named nothing on 24 effect-free recordings.
  double min_val_improvement = 0.03;
  double min_bic_drop = 2.0;        // and BIC decrease (effective sample count; 2 = "positive evidence")
  double samples_per_independent = 5.0;  // residual correlation: samples per independent one
  int max_effects = 3;
  std::vector<std::string> candidates;  // empty = the whole library
};

struct CandidateReport {
  std::string id;
  std::vector<ParamEstimate> params;  // first-round fit (alone on the nominal)
  double val_improvement = 0;         // relative validation-cost reduction (first round)
  double bic_delta = 0;               // BIC(nominal + effect) - BIC(nominal), first round
  double heldout_improvement = 0;     // relative held-out 1-s normalised RMSE reduction
  bool selected = false;
  int round_selected = 0;
};

struct Selection {
  std::vector<std::string> selected;            // in the order chosen
  std::vector<CandidateReport> candidates;      // every candidate tried
  std::vector<ParamEstimate> final_params;      // joint refit of the selected effects
  EffectParams final_effects;
  std::vector<std::string> log;                 // one line per round / decision
};

// Runs the selection on the training rows (train_mask), reporting held-out numbers on
// heldout_mask.
Selection select_effects(const DiagData& d, const ModelFamily& nominal,
                         const std::vector<char>& train_mask, const std::vector<char>& heldout_mask,
                         const SelectionOptions& options = {}, const ReplayOptions& replay = {});

}  // namespace mppi::diagnose
