// Stability selection (selection_stages.hpp): the greedy selection repeated on block-bootstrap
// resamples of the fit part, in parallel; an effect is named only when enough of them choose it.
#include <algorithm>
#include <cmath>
#include <mutex>

#include <tbb/parallel_for.h>

#include "diagnose/selection_stages.hpp"

namespace mppi::diagnose::selection {

std::vector<std::vector<int>> stability_resamples(const Folds& folds, const CandidateSet& cands,
                                                  const std::vector<int>& stable_pool, const GreedyResult& main,
                                                  const SelectionOptions& opt, double n_eff, int segment_rows,
                                                  double dt_s) {
  std::mt19937_64 rng(opt.seed * 0x9E3779B97F4A7C15ull + 17);
  const int block = std::max(2, static_cast<int>(std::lround(2.0 / (segment_rows * dt_s))));  // about 2 s
  // The resamples are drawn in order (one random stream), then selected on in parallel.
  std::vector<FitProblem> resampled(static_cast<std::size_t>(opt.stability_resamples), folds.fit);
  for (FitProblem& fit_b : resampled) fit_b.segments = resample_blocks(folds.fit.segments, block, rng);
  std::vector<std::vector<int>> chosen(resampled.size());
  std::mutex progress_mutex;
  int done = 0;
  tbb::parallel_for(std::size_t(0), resampled.size(), [&](std::size_t b) {
    chosen[b] = greedy({resampled[b], folds.val, folds.early_fit, folds.early_val}, cands, stable_pool, opt, n_eff,
                       nullptr, &main.first_round)
                    .chosen;
    if (opt.progress) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      opt.progress("stability: resample " + std::to_string(++done) + " of " + std::to_string(opt.stability_resamples) + " done");
    }
  });
  return chosen;
}

}  // namespace mppi::diagnose::selection
