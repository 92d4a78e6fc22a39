// report.json of a diagnosis (diagnose/report_json.hpp).
#include "diagnose/report_json.hpp"

#include <cmath>

#include "diagnose/model_comparison.hpp"
#include "diagnose/report_markdown.hpp"

namespace mppi::diagnose {
namespace {

using json = nlohmann::ordered_json;

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// The values screened out of the recording (screen.hpp); at most kMaxListedFlags listed.
json screening_json(const PreparedRecording& d) {
  json flags = json::array();
  for (std::size_t i = 0; i < d.flags.size() && i < kMaxListedFlags; ++i) {
    const ScreenFlag& f = d.flags[i];
    // The value as text: JSON has no NaN or inf.
    char value[32];
    std::snprintf(value, sizeof value, "%.6g", f.value);
    flags.push_back({{"file", f.file}, {"row", f.row}, {"t_s", num(f.t_s)}, {"column", f.column},
                     {"value", value}, {"kind", f.kind}});
  }
  return {{"flagged", d.flags.size()}, {"rows_dropped", d.screened_rows}, {"flags", flags}};
}

// The selected effects that are sensor faults (what the recording shows, not the car).
json sensor_faults_json(const Selection& selection) {
  json faults = json::array();
  for (const auto& id : selection.selected)
    if (effect_spec(id).hook == EffectHook::kSensor) faults.push_back(id);
  return faults;
}

json suspected_json(const Selection& selection) {
  json suspected = json::array();
  for (const auto& s : selection.suspected) {
    json ps;
    for (const auto& p : s.params) ps[p.name] = {{"value", num(p.value)}, {"unit", p.unit}};
    suspected.push_back({{"id", s.id}, {"reason", s.reason}, {"params", ps}});
  }
  return suspected;
}

// Parameter estimates by name: value, 1-sigma and unit (null where there are none).
json estimates_json(const std::vector<ParamEstimate>& params) {
  json ps;
  for (const auto& p : params) ps[p.name] = {{"value", num(p.value)}, {"stddev", num(p.stddev)}, {"unit", p.unit}};
  return ps;
}

// Every candidate considered, each alone on the nominal model.
json candidates_json(const Selection& selection) {
  json effects = json::array();
  for (const auto& c : selection.candidates) {
    json e;
    e["id"] = c.id;
    if (!c.joint_of.empty()) e["joint_of"] = c.joint_of;
    e["params"] = estimates_json(c.params);
    e["validation_improvement"] = num(c.val_improvement);
    e["bic_delta"] = num(c.bic_delta);
    e["heldout_improvement"] = num(c.heldout_improvement);
    e["selected"] = c.selected;
    if (c.selected) e["round"] = c.round_selected;
    if (!c.not_testable.empty()) e["not_testable"] = c.not_testable;
    if (c.inclusion_frequency >= 0) e["inclusion_frequency"] = c.inclusion_frequency;
    effects.push_back(e);
  }
  return effects;
}

// Located mismatch: channel, where, mean, rms and z of each finding.
json mismatch_json(const std::vector<Mismatch>& findings) {
  json out = json::array();
  for (const auto& m : findings)
    out.push_back({{"channel", m.channel}, {"where", m.where}, {"magnitude", num(m.magnitude)},
                   {"rms", num(m.rms)}, {"z", num(m.z)}, {"unit", m.unit}});
  return out;
}

// "one_step" for the sample interval, else the horizon's first four characters and "s" ("0.50s").
std::string horizon_key(double horizon_s, double dt_s) {
  return std::abs(horizon_s - dt_s) < 1e-9 ? "one_step" : (std::to_string(horizon_s).substr(0, 4) + "s");
}

// Fit [%] per horizon and channel.
json fit_by_horizon(const std::vector<HorizonMetrics>& ms, double dt_s) {
  json f;
  for (const auto& m : ms) {
    const std::string k = horizon_key(m.horizon_s, dt_s);
    for (int c = 0; c < kChannels; ++c) f[k][kChannelNames[c]] = num(m.fit_percent[c]);
  }
  return f;
}

// RMSE per horizon and channel, and the normalised RMSE of each horizon.
json rmse_by_horizon(const std::vector<HorizonMetrics>& ms, double dt_s) {
  json f;
  for (const auto& m : ms) {
    const std::string k = horizon_key(m.horizon_s, dt_s);
    for (int c = 0; c < kChannels; ++c) f[k][kChannelNames[c]] = num(m.rmse[c]);
    f[k]["normalized"] = num(m.normalized_rmse);
  }
  return f;
}

json per_recording_json(const std::vector<DiagnoseResult::PartScore>& per_recording) {
  json parts = json::array();
  for (const auto& p : per_recording)
    parts.push_back({{"recording", p.name},
                     {"normalized_rmse_before", num(p.before)},
                     {"normalized_rmse_after", num(p.after)},
                     {"reduction", num(p.before > 0 ? 1.0 - p.after / p.before : 0.0)}});
  return parts;
}

// The scores on the test data (DiagnoseOptions::test, which must be set).
json test_json(const DiagnoseOptions& o, const DiagnoseResult& res) {
  return {{"data", o.test_name.empty() ? o.test->source : o.test_name},
          {"rows", o.test->rows()},
          {"horizon_s", o.headline_horizon_s},
          {"normalized_rmse_before", num(res.test.headline_nominal)},
          {"normalized_rmse_after", num(res.test.headline_corrected)},
          {"reduction", num(res.test.reduction)},
          {"correction_written", res.selection.reliable},
          {"metrics_before", horizon_metrics_json(res.test.nominal)},
          {"metrics_after", horizon_metrics_json(res.test.corrected)}};
}

}  // namespace

nlohmann::ordered_json report_json(const PreparedRecording& d, const std::string& nominal_name, const DiagnoseOptions& o,
                                   const DiagnoseResult& res) {
  json j;
  j["log"] = d.source;
  j["model"] = nominal_name;
  j["params"] = o.params_source;
  j["rows"] = d.rows();
  j["control_loss_rows"] = res.control_loss_rows;
  j["dt_s"] = d.dt_s;
  j["holdout"] = o.holdout;
  j["screening"] = screening_json(d);
  j["selected"] = res.selection.selected;
  j["partial"] = res.selection.partial;
  j["ambiguous"] = res.selection.ambiguous;
  j["reliable"] = res.selection.reliable;
  j["verdict"] = res.selection.verdict;
  j["sensor_faults"] = sensor_faults_json(res.selection);
  j["suspected"] = suspected_json(res.selection);
  j["heldout_1s_normalized_rmse"] = {{"nominal", num(res.selection.heldout_nominal)},
                                     {"corrected", num(res.selection.heldout_corrected)}};
  j["effects"] = candidates_json(res.selection);
  j["final_params"] = estimates_json(res.selection.final_params);
  j["mismatch"] = mismatch_json(res.mismatch);
  j["fit_before"] = fit_by_horizon(res.before, d.dt_s);
  j["fit_after"] = fit_by_horizon(res.after, d.dt_s);
  j["heldout_rmse_before"] = rmse_by_horizon(res.before, d.dt_s);
  j["heldout_rmse_after"] = rmse_by_horizon(res.after, d.dt_s);
  // The headline: on test data where there are some (data that neither the fit nor the veto saw),
  // else on the held-out part, which also decided whether the correction is written.
  const json validation_headline = {{"data", "held-out"},
                                    {"horizon_s", o.headline_horizon_s},
                                    {"normalized_rmse_before", num(res.headline_before)},
                                    {"normalized_rmse_after", num(res.headline_after)},
                                    {"reduction", num(res.heldout_rmse_reduction)}};
  j["validation_headline"] = validation_headline;
  j["headline"] = o.test ? json{{"data", "test"},
                                {"horizon_s", o.headline_horizon_s},
                                {"normalized_rmse_before", num(res.test.headline_nominal)},
                                {"normalized_rmse_after", num(res.test.headline_corrected)},
                                {"reduction", num(res.test.reduction)}}
                         : validation_headline;
  for (int c = 0; c < kChannels; ++c) j["explained_share"][kChannelNames[c]] = num(res.explained_share[c]);
  j["remaining"] = mismatch_json(res.remaining);
  j["remaining_long_horizon"] = mismatch_json(res.remaining_long);
  j["unexplained"] = mismatch_json(res.unexplained);
  j["per_recording"] = per_recording_json(res.per_recording);
  if (o.test) j["test"] = test_json(o, res);
  j["metrics_before"] = horizon_metrics_json(res.before);
  j["metrics_after"] = horizon_metrics_json(res.after);
  j["selection_log"] = res.selection.log;
  j["model_file"] = res.model_file;
  return j;
}

}  // namespace mppi::diagnose
