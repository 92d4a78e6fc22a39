#pragma once
// The stages of select_effects (diagnose/fit.hpp), for its own files: the forward rounds with
// backward elimination and the re-try of an actuator's dynamics forms (selection_rounds.cpp), and
// stability selection over block-bootstrap resamples (selection_stability.cpp). Internal: the
// public entry point is select_effects.
#include <deque>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "diagnose/fit.hpp"
#include "diagnose/joint_refit.hpp"

namespace mppi::diagnose::selection {

// The validation folds, forward in time: the main one (fit, then the later block), and an earlier
// one (the fit part's first half, then its second half) that judges a candidate the later block
// cannot judge: one that changes the later block's cost by less than opt.inconclusive_share (it
// acts on a place, a regime or a stretch of time that the later block does not reach).
struct Folds {
  const FitProblem& fit;
  const FitProblem& val;
  const FitProblem& early_fit;
  const FitProblem& early_val;
};

// The selection log: keeps each line (Selection::log) and echoes it as progress when asked.
class SelectionLog {
 public:
  SelectionLog(std::vector<std::string>* lines, const SelectionOptions& opt) : lines_(lines), progress_(&opt.progress) {}
  void push_back(const std::string& line) {
    if (lines_) lines_->push_back(line);
    if (*progress_) (*progress_)(line);
  }

 private:
  std::vector<std::string>* lines_;
  const std::function<void(const std::string&)>* progress_;
};

// The library effects a candidate stands for: itself, or for a joint candidate its two partners.
using Members = std::vector<std::vector<int>>;

// What the rounds choose from: the candidates (library effects, then joint ones) and their members.
struct CandidateSet {
  const std::vector<const EffectSpec*>& specs;
  const Members& members;
  const EffectSpec& operator[](int i) const { return *specs[static_cast<std::size_t>(i)]; }
};

struct CandidateFit {
  int index = -1;  // into the candidate list
  FitResult fit;
  double val_cost = 0, improvement = 0, bic = 0;
  bool passes = false;
  bool judged_early = false;  // passed on the earlier fold (the later block could not judge it)
  std::string earlier_fold;   // for the log: the earlier fold's verdict where it was asked
};

struct GreedyResult {
  std::vector<int> chosen;  // candidate indices in the order chosen
  EffectParams effects;
  std::vector<CandidateFit> first_round;  // every candidate of the pool, alone on the nominal
  std::vector<std::pair<int, std::string>> at_limit;  // passed, but a parameter is a bound
  std::vector<int> passed;  // every candidate that passed in some round
  // The fitted state after each round (its chosen effects refitted together), before backward
  // elimination: the ids chosen by then, and the effects.
  std::vector<SelectionRound> rounds;
};

// The parameters of these candidates that a joint least-squares refit moves at `at`: all but a
// change time, which was searched over the data, and an optional disc that is not there.
std::vector<ParamSpec> joint_free_params(const std::vector<const EffectSpec*>& cands, const std::vector<int>& chosen,
                                         const EffectParams& at);
// Effect parameters of `ids` copied from `from`, everything else at its default.
EffectParams only(const std::vector<std::string>& ids, const EffectParams& from);
std::vector<std::string> ids_of(const std::vector<const EffectSpec*>& cands, const std::vector<int>& chosen);

// The training rows as fit problems: all segments, the fit part and the later block that
// validates it, and the earlier fold (the fit part's halves).
struct Problems {
  FitProblem all, fit, val, early_fit, early_val;
  int len = 0;       // rows per segment
  double n_eff = 0;  // the fit part's effective sample count (the BIC's)
};

void make_problems(const PreparedRecording& d, const ModelFamily& nominal, const std::vector<char>& train_mask,
                   const SelectionOptions& opt, const ReplayOptions& replay, Problems* p, SelectionLog& log);

// The candidates: the library's (or those asked for) that the nominal model takes, then the joint
// ones of partner terms. joint_specs holds the joint candidates' specs (stable addresses).
void make_candidates(const ModelFamily& nominal, const SelectionOptions& opt, std::vector<const EffectSpec*>* out,
                     Members* members_out, std::deque<EffectSpec>* joint_specs);

// Greedy forward selection over `pool` (indices into the candidates): each round fits every
// remaining candidate on top of what is chosen and takes the one that lowers the validation cost
// most (the simplest among those nearly as good) among those that lower it enough and the BIC
// too, with identified parameters; a time-indexed change gives way to a state-dependent candidate
// that explains most of the same. Then backward elimination and the re-try of the dynamics forms.
// n_eff: the fit part's effective sample count (the BIC's). `log` may be nullptr.
// `place_starts`: where given (a resample's selection), each place-dependent candidate is also
// refined from the place that the selection on all the data found for it, and keeps the better
// fit. A resample holds about two thirds of the data's blocks, fewer passes over the place, and the
// search over places alone then lands elsewhere as often as not: stability should ask whether the
// resample's data support the effect, not whether a search from scratch finds it again.
GreedyResult greedy(const Folds& folds, const CandidateSet& cands, const std::vector<int>& pool,
                    const SelectionOptions& opt, double n_eff, SelectionLog* log,
                    const std::vector<CandidateFit>* place_starts = nullptr);

// Block bootstrap of segments: blocks of consecutive segments drawn with replacement.
std::vector<Segment> resample_blocks(const std::vector<Segment>& segs, int block, std::mt19937_64& rng);

// Stability selection: the greedy selection repeated on opt.stability_resamples block-bootstrap
// resamples of the fit part (blocks of about 2 s) over `stable_pool`; what each chose.
std::vector<std::vector<int>> stability_resamples(const Folds& folds, const CandidateSet& cands,
                                                  const std::vector<int>& stable_pool, const GreedyResult& main,
                                                  const SelectionOptions& opt, double n_eff, int segment_rows,
                                                  double dt_s);

}  // namespace mppi::diagnose::selection
