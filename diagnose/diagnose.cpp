#include "diagnose/diagnose.hpp"
#include "diagnose/evaluate.hpp"
#include "diagnose/model_comparison.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <optional>

#include <nlohmann/json.hpp>

#include "plot/figure_json.hpp"
#include "plot/html_report.hpp"

#include "base/error.hpp"
#include "diagnose/control_loss.hpp"
#include "diagnose/plots.hpp"
#include "diagnose/report_json.hpp"
#include "diagnose/report_markdown.hpp"

namespace mppi::diagnose {

using json = nlohmann::ordered_json;

namespace {

// Leaves the rows of lost control out of *select_rows (the training rows) where enough is left,
// and counts those among the training rows in *lost_training_rows. Returns the selection log's line
// about them (empty where there are none).
std::string leave_out_control_loss(const PreparedRecording& d, const std::vector<char>& train, const DiagnoseOptions& o,
                                   std::vector<char>* select_rows, std::size_t* lost_training_rows) {
  const std::vector<char> lost = control_loss_rows(d, o.control_loss);
  std::size_t n_train = 0;
  for (std::size_t k = 0; k < d.rows(); ++k) {
    n_train += train[k] != 0;
    *lost_training_rows += train[k] && lost[k];
  }
  if (*lost_training_rows == 0) return std::string();
  for (std::size_t k = 0; k < d.rows(); ++k)
    if (lost[k]) (*select_rows)[k] = 0;
  const int len = std::max(2, static_cast<int>(std::lround(o.selection.fit_horizon_s / d.dt_s)));
  const bool enough =
      static_cast<double>(*lost_training_rows) < o.control_loss.max_share_left_out * static_cast<double>(n_train) &&
      make_segments(d, *select_rows, len, len).size() >= static_cast<std::size_t>(o.control_loss.min_segments_left);
  char line[320];
  std::snprintf(line, sizeof line,
                "%zu of %zu training rows (%.1f %%) are lost control "
                "(body slip > %.0f deg above %.1f m/s, and %.1f s around): %s",
                *lost_training_rows, n_train,
                100.0 * static_cast<double>(*lost_training_rows) / static_cast<double>(n_train),
                o.control_loss.max_body_slip_deg, o.control_loss.min_speed_mps, o.control_loss.guard_s,
                enough ? "left out of the fits and their validation" : "kept (too little would be left)");
  const std::string control_loss_line = line;
  if (!enough) *select_rows = train;
  if (o.selection.progress) o.selection.progress(control_loss_line);
  return control_loss_line;
}

// The held-out scores: one-step, then the multi-step horizons; the headline and the explained
// share; per held-out recording.
void score_heldout(const PreparedRecording& d, const ReplayModel& nominal_model, const ReplayModel& corrected,
                   const std::vector<char>& held, const DiagnoseOptions& o, DiagnoseResult* res) {
  std::vector<double> hs = {d.dt_s};
  hs.insert(hs.end(), o.horizons_s.begin(), o.horizons_s.end());
  res->before = horizon_metrics(nominal_model, d, held, hs, 5, o.replay);
  res->after = horizon_metrics(corrected, d, held, hs, 5, o.replay);
  const HorizonMetrics* hb = at_horizon(res->before, o.headline_horizon_s);
  const HorizonMetrics* ha = at_horizon(res->after, o.headline_horizon_s);
  if (hb && ha) {
    res->headline_before = hb->normalized_rmse;
    res->headline_after = ha->normalized_rmse;
    res->heldout_rmse_reduction = hb->normalized_rmse > 0 ? 1.0 - ha->normalized_rmse / hb->normalized_rmse : 0.0;
    for (int c = 0; c < kChannels; ++c)
      res->explained_share[c] = hb->rmse[c] > 0 ? 1.0 - (ha->rmse[c] / hb->rmse[c]) * (ha->rmse[c] / hb->rmse[c]) : 0.0;
  }
  for (const auto& part : o.heldout_recordings) {
    std::vector<char> mask(d.rows(), 0);
    for (std::size_t k = 0; k < d.rows(); ++k) mask[k] = held[k] && d.t[k] >= part.t0_s && d.t[k] <= part.t1_s;
    const auto b = horizon_metrics(nominal_model, d, mask, {o.headline_horizon_s}, 5, o.replay);
    const auto a = horizon_metrics(corrected, d, mask, {o.headline_horizon_s}, 5, o.replay);
    if (!b.empty() && !a.empty()) res->per_recording.push_back({part.name, b[0].normalized_rmse, a[0].normalized_rmse});
  }
}

// OUT/corrected_model.yaml where the correction is reliable (its path in res->model_file); where
// it is not, any earlier one is removed.
void write_corrected_model(const PreparedRecording& d, const ModelFamily& nominal, const DiagnoseOptions& o,
                           DiagnoseResult* res) {
  std::vector<std::string> in_model = res->selection.selected;  // named, or a partial correction
  in_model.insert(in_model.end(), res->selection.partial.begin(), res->selection.partial.end());
  CorrectedModelFile file = nominal.file(res->selection.final_effects, in_model);
  file.fitted_on = fitted_on_of(d);
  file.fitted_on["heldout"] = o.holdout;
  // The controller has no clock of the recording: a grip change is written as the grip after it.
  if (file.effects.grip_change_time_s > 0 && file.effects.grip_scale != 1.0) {
    file.effects.grip_change_time_s = 0.0;
  }
  if (!o.out_dir.empty()) std::filesystem::create_directories(o.out_dir);
  if (!o.out_dir.empty() && !res->selection.reliable) {
    std::filesystem::remove(o.out_dir + "/corrected_model.yaml");  // none is trusted: none is left behind
  } else if (!o.out_dir.empty()) {
    res->model_file = o.out_dir + "/corrected_model.yaml";
    std::ofstream mf(res->model_file);
    if (!mf) throw Error("cannot write " + res->model_file);
    mf << corrected_model_to_yaml(file, "corrected model written by mppi-fit diagnose from " + d.source +
                                            "\nload with: mppi-sim --model corrected --model-params <this file>");
  }
}

// What the report's figures show: the residuals before and after, the two models and the held-out rows.
struct FigureInputs {
  const ResidualSeries& before;
  const ResidualSeries& after;
  const ReplayModel& nominal_model;
  const ReplayModel& corrected;
  const std::vector<char>& held;
};

// report.json (also in res->json), and in OUT report.md, the PNGs and report.html.
void write_reports(const PreparedRecording& d, const std::string& nominal_name, const DiagnoseOptions& o,
                   const FigureInputs& f, DiagnoseResult* res) {
  json j = report_json(d, nominal_name, o, *res);
  // The report's figures: the same data in report.json, the PNGs and report.html.
  std::optional<plot::Figure> regime_fig, overlay_fig;
  if (!o.out_dir.empty() && o.plots) {
    regime_fig = residual_vs_regime_figure(d, f.before, f.after, f.held);
    overlay_fig = overlay_figure(d, f.nominal_model, f.corrected, f.held, o.replay);
    j["figures"] = {{"residual_vs_regime", plot::figure_to_json(*regime_fig)},
                    {"overlay", plot::figure_to_json(*overlay_fig)}};
  }
  res->json = j.dump(2);

  if (!o.out_dir.empty()) {
    std::ofstream(o.out_dir + "/report.json") << res->json << "\n";
    const std::string md = report_markdown(d, nominal_name, o, *res, f.before.horizon_s);
    std::ofstream(o.out_dir + "/report.md") << md;
    if (o.plots) {
      regime_fig->write_png(o.out_dir + "/residual_vs_regime.png");
      overlay_fig->write_png(o.out_dir + "/overlay.png");
      plot::write_html_report(o.out_dir + "/report.html", "Sim-vs-real diagnosis", md,
                              {{"residual_vs_regime.png", j["figures"]["residual_vs_regime"]},
                               {"overlay.png", j["figures"]["overlay"]}});
    }
  }
}

}  // namespace

DiagnoseResult run_diagnosis(const PreparedRecording& d, const ModelFamily& nominal, const DiagnoseOptions& o) {
  DiagnoseResult res;
  const Split split = make_split(d, o.holdout);
  std::vector<char> train(d.rows()), held = split.heldout;
  for (std::size_t k = 0; k < d.rows(); ++k) train[k] = !held[k];
  const auto nominal_ptr = nominal.make({});
  const ReplayModel& nominal_model = *nominal_ptr;

  // 1. Locate (training part: the held-out part is kept for judging the correction).
  const ResidualSeries rs = residual_series(nominal_model, d, o.locate_horizon_s, o.replay);
  res.mismatch = locate(d, rs, train);

  // 2. Name, without the rows of lost control where enough is left.
  std::vector<char> select_rows = train;
  const std::string control_loss_line = leave_out_control_loss(d, train, o, &select_rows, &res.control_loss_rows);
  res.selection = select_effects(d, nominal, select_rows, held, o.selection, o.replay);
  if (!control_loss_line.empty()) res.selection.log.insert(res.selection.log.begin(), control_loss_line);
  const auto corrected_ptr = nominal.make(res.selection.final_effects);
  const ReplayModel& corrected = *corrected_ptr;

  // 4. Show (held out): one-step, then the multi-step horizons.
  score_heldout(d, nominal_model, corrected, held, o, &res);
  // The test part: data the selection never saw, scored whatever the veto decided.
  if (o.test)
    res.test = compare_models(nominal_model, corrected, *o.test, std::vector<char>(o.test->rows(), 1), o.horizons_s,
                              o.headline_horizon_s, o.replay);
  // What is left: the corrected model's residuals, located on the held-out part.
  const ResidualSeries rs_after = residual_series(corrected, d, o.locate_horizon_s, o.replay);
  res.remaining = locate(d, rs_after, held);
  std::vector<Mismatch> nominal_long;
  if (o.unexplained.long_horizon_s > 0) {
    const std::vector<char> all_rows(d.rows(), 1);
    nominal_long = locate(d, residual_series(nominal_model, d, o.unexplained.long_horizon_s, o.replay), all_rows);
    res.remaining_long = locate(d, residual_series(corrected, d, o.unexplained.long_horizon_s, o.replay), all_rows);
  }
  const std::vector<Mismatch> long_look = long_horizon_unexplained(nominal_long, res.remaining_long, o.unexplained);
  res.unexplained = unexplained_of_both(res.mismatch, res.remaining, long_look, o.unexplained);
  mark_partial_where_unexplained(long_look, &res.selection);

  // 3. Model file.
  write_corrected_model(d, nominal, o, &res);

  write_reports(d, nominal.name(), o, {rs, rs_after, nominal_model, corrected, held}, &res);
  return res;
}

}  // namespace mppi::diagnose
