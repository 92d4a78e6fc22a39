#pragma once
// Naming the missing physics: nonlinear least squares fits of candidate effects (Levenberg-
// Marquardt with parameter uncertainties from the Jacobian; time-like parameters by grid
// search) on multi-step open-loop residuals, and greedy forward selection judged on
// validation segments with the BIC, so that an effect that does not help is not named.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "diagnose/candidate_effects.hpp"
#include "diagnose/data.hpp"
#include "diagnose/model_family.hpp"
#include "diagnose/replay.hpp"

namespace mppi::diagnose {

// Defaults that a fit problem and the selection share (SelectionOptions explains them).
inline constexpr double kDefaultSamplesPerIndependent = 5.0;
inline constexpr double kDefaultMinImprovement = 0.03;

// The data a fit works on: segments and channel scales.
struct FitProblem {
  const PreparedRecording* data = nullptr;
  const ModelFamily* family = nullptr;  // the nominal model; members = nominal + effects
  std::vector<Segment> segments;
  std::array<double, kChannels> scale{};
  ReplayOptions replay;
  // Multi-step residuals are correlated: samples per independent one, by which a fit's parameter
  // covariance is inflated (SelectionOptions::samples_per_independent).
  double samples_per_independent = kDefaultSamplesPerIndependent;
  // The cost reduction that counts as seen (SelectionOptions::min_val_improvement): a further disc
  // of a place-dependent effect is kept only where it lowers the fit cost by this share.
  double min_cost_gain = kDefaultMinImprovement;
};

// The family's member with these effects, or nullptr where the values make it invalid.
std::unique_ptr<ReplayModel> make_member_or_null(const ModelFamily& family, const EffectParams& e);

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

// Parameters of a fitted candidate that the data use (at least 1): a parameter within two
// standard deviations of its default (where it is off) is one the fit could leave out, so it
// does not count against the candidate's simplicity (F0 + b v with b ~ 0 is as simple as
// c v^2). Parameters searched over the data (a time, a place) always count.
std::size_t used_param_count(const EffectSpec& spec, const FitResult& fit);

// Fits the free parameters `free` starting from `base` (whose other fields stay fixed).
FitResult fit_params(const FitProblem& p, const EffectParams& base, const std::vector<ParamSpec>& free,
                     int max_iterations = 15);

// The parameters of `spec` that a fit moves at `e`: all but the optional discs `e` does not have.
std::vector<ParamSpec> active_params(const EffectSpec& spec, const EffectParams& e);

// A place-dependent effect (grip_patch): its place searched over where the car went, then LM;
// further discs of the same surface added while each lowers the cost clearly.
FitResult fit_place_effect(const FitProblem& p, const EffectParams& base, const EffectSpec& spec);

// The same effect refined by least squares from a known place and shape (`start`'s values of the
// effect's parameters; everything else from `base`), without the search.
FitResult fit_place_effect_from(const FitProblem& p, const EffectParams& base, const EffectSpec& spec,
                                const EffectParams& start);

// One effect (spec) on top of base: start-value grid search, then LM.
FitResult fit_effect(const FitProblem& p, const EffectParams& base, const EffectSpec& spec);

struct SelectionOptions {
  double fit_horizon_s = 0.5;       // multi-step horizon of the fit residuals [s]
  // Relative validation-cost reduction an effect must give. The cost includes sensor noise, so
  // a barely visible effect moves it by a few %; 3 % named nothing on 24 effect-free recordings.
  double min_val_improvement = kDefaultMinImprovement;
  double min_bic_drop = 2.0;        // and BIC decrease (effective sample count; 2 = "positive evidence")
  double samples_per_independent = kDefaultSamplesPerIndependent;  // residual correlation: samples per independent one
  // Selection rounds at most; each names one candidate, which may be joint (steer_gain+steer_offset,
  // motor_freewheel+drag_brake). A real car can miss several things at once (delays, the ESC's
  // neutral, the weight distribution, the tyre): every round must still pass the gain, BIC and
  // stability thresholds, so the cap only bounds the run time.
  int max_effects = 5;
  std::vector<std::string> candidates;  // empty = the whole library
  // Forward validation: the last part of the training data (in time) judges what the earlier
  // part fitted, so an effect must hold on data that come later.
  double validation_fraction = 0.3;
  // A candidate that changes the later block's validation cost by less than this share cannot be
  // judged there; the earlier fold (the fit part's first half judging its second half) does.
  double inconclusive_share = 0.03;
  // Stability selection: the selection is repeated on block-bootstrap resamples of the fit
  // segments; an effect is named only when chosen in at least this share of them.
  int stability_resamples = 6;
  double min_inclusion_frequency = 0.65;
  // Substitutes: where a named effect and an effect outside the selection (and outside its
  // actuator's dynamics) never appear in one resample and some resample took the other in its
  // place, the data hold two physical explanations (a term that mimics a missing one, e.g. a
  // throttle gain where the car carries a payload). That effect is then part of a partial
  // correction (Selection::partial, Selection::ambiguous), not a name.
  bool withhold_substituted = true;
  std::uint64_t seed = 1;
  double range_limit_margin = 0.01;  // fraction of a search range that counts as "at its end"
  // A time-indexed change is named only when no state-dependent candidate explains at least
  // this share of its validation improvement.
  double time_change_dominance = 0.8;
  // Parsimony: a candidate with fewer parameters is preferred when its validation improvement is
  // at least this share of the best one's.
  double parsimony_share = 0.9;
  // Among near-best candidates of as many parameters, one whose BIC on the fit part is lower by
  // at least this ("strong evidence" on the Kass-Raftery scale) goes first.
  double strong_bic_evidence = 6.0;
  // Called with each line of the selection log as it is written, and as each stability resample
  // finishes (a run takes minutes): progress output. Empty = silent. Calls come one at a time,
  // but not always from the calling thread.
  std::function<void(const std::string&)> progress;
};

struct CandidateReport {
  std::string id;
  std::vector<std::string> joint_of;  // a joint candidate: the library effects fitted together (else empty)
  std::vector<ParamEstimate> params;  // first-round fit (alone on the nominal)
  double val_improvement = 0;         // relative validation-cost reduction (first round)
  double bic_delta = 0;               // BIC(nominal + effect) - BIC(nominal), first round
  double heldout_improvement = 0;     // relative held-out 1-s normalised RMSE reduction
  bool selected = false;
  int round_selected = 0;
  std::string not_testable;           // why the recording cannot identify it (then not fitted)
  double inclusion_frequency = -1;    // share of stability resamples that chose it (-1: not resampled)
};

// An effect the data point to but do not pin down: reported, not named, not in the model file.
struct SuspectedEffect {
  std::string id;
  std::string reason;
  std::vector<ParamEstimate> params;
};

struct Selection {
  std::vector<std::string> selected;            // named, in the order chosen
  // Chosen but not named: they explain a mismatch only in part, and a part no candidate explains
  // remains (unexplained.hpp). They are in final_effects and the model file.
  std::vector<std::string> partial;
  // Named effects and their substitutes in the stability resamples ("a or b; c or d"; empty:
  // none): the part of `partial` that the data cannot tell from another physics
  // (diagnose/substitutes.hpp).
  std::string ambiguous;
  std::vector<CandidateReport> candidates;      // every candidate considered
  std::vector<SuspectedEffect> suspected;       // "suspected, not identifiable from this recording"
  std::vector<ParamEstimate> final_params;      // joint refit of the selected effects
  EffectParams final_effects;
  bool reliable = true;                         // false: "no reliable correction" (none written)
  std::string verdict;                          // one line: what was concluded
  double heldout_nominal = 0, heldout_corrected = 0;  // held-out 1-s normalised RMSE
  std::vector<std::string> log;                 // one line per round / decision
};

// Runs the selection on the training rows (train_mask) and judges the corrected model on the
// held-out rows (heldout_mask): when it is not better than the nominal there, nothing is named.
Selection select_effects(const PreparedRecording& d, const ModelFamily& nominal,
                         const std::vector<char>& train_mask, const std::vector<char>& heldout_mask,
                         const SelectionOptions& options = {}, const ReplayOptions& replay = {});

}  // namespace mppi::diagnose
