// report.md of a diagnosis (diagnose/report_markdown.hpp).
#include "diagnose/report_markdown.hpp"

#include <cmath>
#include <sstream>

namespace mppi::diagnose {

namespace {

// The recording, the models, the verdict and the headline figures.
void write_summary(std::ostream& md, const PreparedRecording& d, const std::string& nominal_name, const DiagnoseOptions& o,
                   const DiagnoseResult& res) {
  md << "# Sim-vs-real diagnosis\n\n"
     << "- recording: `" << d.source << "` (" << d.rows() << " rows, dt " << d.dt_s << " s), held out: `" << o.holdout
     << "`\n- nominal model: " << nominal_name
     << (o.params_source.empty() ? " (library defaults)" : " from `" + o.params_source + "`")
     << "\n- corrected model: " << (res.model_file.empty() ? std::string("none written") : "`" + res.model_file + "`")
     << "\n- verdict: **" << res.selection.verdict << "**\n"
     << "- unexplained mismatch (clear in the corrected model's residual, no named effect explains it): "
     << unexplained_summary(res.unexplained) << "\n";
  if (!res.selection.partial.empty()) {
    md << "- partial correction (in the model file; not named: a mismatch remains that none explains, or the data "
          "hold another physics that explains it as well"
       << (res.selection.ambiguous.empty() ? "" : ": " + res.selection.ambiguous) << "):";
    for (const auto& id : res.selection.partial) md << " " << id;
    md << "\n";
  }
  // The figure a user should trust first: on data that neither the fit nor the veto saw.
  if (o.test)
    md << "- **headline (test data, never seen by the fit or the validation):** normalised RMSE at "
       << o.headline_horizon_s << " s " << res.test.headline_nominal << " -> " << res.test.headline_corrected << " ("
       << 100 * res.test.reduction << " % reduction)\n";
  md << "- held out (" << (o.test ? "also the veto" : "headline") << "): normalised RMSE at " << o.headline_horizon_s
     << " s " << res.headline_before << " -> " << res.headline_after << " (" << 100 * res.heldout_rmse_reduction
     << " % reduction)\n\n";
}

// The values screened out of the recording (screen.hpp); at most kMaxListedFlags listed.
void write_screened_values(std::ostream& md, const PreparedRecording& d) {
  if (d.flags.empty()) return;
  md << "## Screened values (kept out of the fits)\n\n" << d.flags.size() << " values flagged; "
     << d.screened_rows << " rows dropped with their neighbours.\n\n"
     << "| file | row | t [s] | column | value | kind |\n|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < d.flags.size() && i < kMaxListedFlags; ++i) {
    const ScreenFlag& f = d.flags[i];
    md << "| " << f.file << " | " << f.row << " | " << f.t_s << " | " << f.column << " | " << f.value << " | " << f.kind
       << " |\n";
  }
  if (d.flags.size() > kMaxListedFlags) md << "\n(first " << kMaxListedFlags << " listed; all in the counts)\n";
  md << "\n";
}

// How often stability selection chose the effect, where it ran; empty otherwise.
std::string inclusion_note(const Selection& selection, const std::string& id) {
  for (const auto& c : selection.candidates)
    if (c.id == id && c.inclusion_frequency >= 0)
      return " (chosen in " + std::to_string(std::lround(100 * c.inclusion_frequency)) + " % of resamples)";
  return std::string();
}

// The selected effects: missing physics first, then sensor faults.
void write_named_effects(std::ostream& md, const Selection& selection) {
  md << "## Named effects\n\n";
  int physics = 0, sensors = 0;
  for (const auto& id : selection.selected) (effect_spec(id).hook == EffectHook::kSensor ? sensors : physics)++;
  if (physics == 0) md << "No missing physics named.\n";
  for (const auto& id : selection.selected)
    if (effect_spec(id).hook != EffectHook::kSensor)
      md << "- **" << id << "**: " << effect_spec(id).description << inclusion_note(selection, id) << "\n";
  if (sensors > 0) {
    md << "\n## Sensor faults (what the recording shows, not the car)\n\n";
    for (const auto& id : selection.selected)
      if (effect_spec(id).hook == EffectHook::kSensor)
        md << "- **" << id << "**: " << effect_spec(id).description << inclusion_note(selection, id) << "\n";
  }
}

void write_suspected(std::ostream& md, const Selection& selection) {
  if (selection.suspected.empty()) return;
  md << "\n## Suspected, not identifiable from this recording\n\n| effect | why not named | fitted |\n|---|---|---|\n";
  for (const auto& s : selection.suspected) {
    md << "| " << s.id << " | " << s.reason << " | ";
    for (const auto& p : s.params) md << p.name << " = " << p.value << "; ";
    md << " |\n";
  }
}

// The first `limit` located findings as table rows: channel, where, mean, rms, z.
void write_mismatch_rows(std::ostream& md, const std::vector<Mismatch>& findings, std::size_t limit) {
  for (std::size_t i = 0; i < findings.size() && i < limit; ++i) {
    const auto& m = findings[i];
    md << "| " << m.channel << " | " << m.where << " | " << m.magnitude << " " << m.unit << " | " << m.rms << " | "
       << m.z << " |\n";
  }
}

void write_candidates(std::ostream& md, const Selection& selection) {
  md << "\n## Candidates (each alone on the nominal model)\n\n"
        "| effect | params | validation improvement | dBIC | held-out improvement | inclusion | selected |\n"
        "|---|---|---|---|---|---|---|\n";
  for (const auto& c : selection.candidates) {
    if (!c.not_testable.empty()) {
      md << "| " << c.id << " | not testable: " << c.not_testable << " | | | | | |\n";
      continue;
    }
    md << "| " << c.id << " | ";
    for (const auto& p : c.params) md << p.name << " = " << p.value << " +- " << p.stddev << "; ";
    md << " | " << 100 * c.val_improvement << " % | " << c.bic_delta << " | " << 100 * c.heldout_improvement << " % | "
       << (c.inclusion_frequency >= 0 ? std::to_string(std::lround(100 * c.inclusion_frequency)) + " %" : "") << " | "
       << (c.selected ? "yes" : "") << " |\n";
  }
}

void write_heldout_fit(std::ostream& md, const DiagnoseResult& res) {
  md << "\n## Held-out fit before -> after\n\n"
        "| horizon | channel | fit % before | fit % after | RMSE before | RMSE after |\n|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < res.before.size(); ++i)
    for (int c = 0; c < kChannels; ++c)
      md << "| " << res.before[i].horizon_s << " s | " << kChannelNames[c] << " | " << res.before[i].fit_percent[c]
         << " | " << res.after[i].fit_percent[c] << " | " << res.before[i].rmse[c] << " | " << res.after[i].rmse[c]
         << " " << kChannelUnits[c] << " |\n";
}

// Per held-out recording: the normalised RMSE of both models; empty without several.
std::string per_recording_table(const DiagnoseOptions& o, const DiagnoseResult& res) {
  if (res.per_recording.empty()) return std::string();
  std::ostringstream t;
  t.precision(4);
  t << "Per held-out recording (normalised RMSE at " << o.headline_horizon_s
    << " s):\n\n| recording | nominal | corrected | reduction |\n|---|---|---|---|\n";
  for (const auto& p : res.per_recording)
    t << "| `" << p.name << "` | " << p.before << " | " << p.after << " | "
      << 100 * (p.before > 0 ? 1.0 - p.after / p.before : 0.0) << " % |\n";
  return t.str() + "\n";
}

// The headline on the test data; empty without test data.
std::string test_headline(const DiagnoseOptions& o, const DiagnoseResult& res) {
  if (!o.test) return std::string();
  std::ostringstream t;
  t.precision(4);
  t << "**Headline, on test data** (" << (o.test_name.empty() ? o.test->source : o.test_name)
    << ", data that neither the fit nor the validation saw): normalised RMSE at " << o.headline_horizon_s
    << " s " << res.test.headline_nominal << " -> " << res.test.headline_corrected << " ("
    << 100 * res.test.reduction << " % reduction)"
    << (res.selection.reliable ? "" : "; this correction was not written (no reliable correction)") << ".\n\n";
  return t.str();
}

// The share of the error the correction explains and where the corrected model is still wrong.
void write_what_is_left(std::ostream& md, const DiagnoseOptions& o, const DiagnoseResult& res) {
  md << "## What is left\n\nShare of the held-out squared error at " << o.headline_horizon_s
     << " s that the correction explains:";
  for (int c = 0; c < kChannels; ++c)
    md << " " << kChannelNames[c] << " " << 100 * res.explained_share[c] << " %" << (c + 1 < kChannels ? "," : ".");
  md << "\n\n";
  if (res.remaining.empty()) {
    md << "The corrected model's residuals on the held-out part show no bias by channel, regime, place or time "
          "(|z| < 4).\n\n";
  } else {
    md << "Where the corrected model is still wrong (held-out part):\n\n"
          "| channel | where | mean | rms | z |\n|---|---|---|---|---|\n";
    write_mismatch_rows(md, res.remaining, 10);
    md << "\n";
  }
}

}  // namespace

std::string report_markdown(const PreparedRecording& d, const std::string& nominal_name, const DiagnoseOptions& o,
                            const DiagnoseResult& res, double residual_horizon_s) {
  std::ostringstream md;
  md.precision(4);
  write_summary(md, d, nominal_name, o, res);
  write_screened_values(md, d);
  write_named_effects(md, res.selection);
  write_suspected(md, res.selection);
  md << "\nFinal parameters (joint refit, 1-sigma):\n\n| parameter | value | stddev | unit |\n|---|---|---|---|\n";
  for (const auto& p : res.selection.final_params)
    md << "| " << p.name << " | " << p.value << " | " << p.stddev << " | " << p.unit << " |\n";
  md << "\n## Where the nominal model is wrong (training part, " << residual_horizon_s
     << " s predictions, acceleration error)\n\n| channel | where | mean | rms | z |\n|---|---|---|---|---|\n";
  write_mismatch_rows(md, res.mismatch, 25);
  write_candidates(md, res.selection);
  write_heldout_fit(md, res);
  md << "\n" << (o.test ? "Held out (the part that also decided whether the correction is written)" : "Headline")
     << ": normalised multi-step RMSE at " << o.headline_horizon_s << " s: " << res.headline_before << " -> "
     << res.headline_after << " (" << 100 * res.heldout_rmse_reduction << " % reduction).\n\n"
     << per_recording_table(o, res) << test_headline(o, res);
  write_what_is_left(md, o, res);
  md << "![residual vs regime](residual_vs_regime.png)\n\n![overlay](overlay.png)\n\n## Selection log\n\n```\n";
  for (const auto& l : res.selection.log) md << l << "\n";
  md << "```\n";
  return md.str();
}

}  // namespace mppi::diagnose
