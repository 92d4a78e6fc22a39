// The sysid tools in the Python module `mppi` (registered from mppi_py.cpp when the libraries
// mppi_sysid and mppi_diagnose are built): real-recording conversion, bifilar inertia, the simulated estimation
// protocol, ALM-UKF / UKF parameter estimation and validation, and sim-vs-real diagnosis.
// They mirror the `mppi-fit` sub-commands (apps/mppi_fit_*.cpp) with the same defaults, so
// the same input gives the same numbers. The GIL is released while C++ computes; mppi::Error
// becomes mppi.Error.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "dynamics/vehicle_params.hpp"
#include "dynamics/model_registry.hpp"
#include "base/error.hpp"
#include "sim/data_dir.hpp"
#include "sim/recording.hpp"
#include "sysid/bifilar.hpp"
#include "sysid/estimable_models.hpp"
#include "diagnose/diagnose.hpp"
#include "diagnose/synth.hpp"
#include "sysid/protocol.hpp"
#include "sysid/real_data.hpp"
#include "sysid/vehicle_estimation.hpp"

namespace py = pybind11;

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

DoubleArray to_array(const std::vector<double>& v) {
  DoubleArray a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

// Same shape as mppi.read_recording.
py::dict recording_dict(const mppi::sim::Recording& r) {
  py::dict columns;
  for (std::size_t c = 0; c < r.columns.size(); ++c) columns[py::str(r.columns[c])] = to_array(r.data[c]);
  py::dict out;
  out["metadata"] = r.metadata;
  out["columns"] = columns;
  out["column_names"] = r.columns;
  return out;
}

// "real/<file>" (optionally ".zip:<member>") names a shipped recording in the data folder,
// as in mppi-fit; anything else is a path (or "archive.zip:member").
std::string resolve(const std::string& spec) {
  if (spec.rfind("real/", 0) != 0) return spec;
  const std::size_t z = spec.find(".zip:");
  return z == std::string::npos ? mppi::sim::data_file(spec)
                                : mppi::sim::data_file(spec.substr(0, z + 4)) + spec.substr(z + 4);
}

mppi::sim::Recording load(const std::string& spec) {
  const std::string path = resolve(spec);
  py::gil_scoped_release release;
  return mppi::sysid::load_any_recording(path);
}

// ---- estimation: the model spec as mppi-fit estimate builds it ----
mppi::sysid::VehicleModelSpec make_spec(const std::string& model, const std::string& params_file,
                                        std::vector<std::string> names, bool keep_wheelbase) {
  return mppi::sysid::with_estimable_model(model, [&]<class E>() {
    const std::string file = params_file.empty() ? mppi::sim::data_file(E::kEstimationFile) : params_file;
    if (names.empty()) names = E::default_estimated();
    return E::spec(E::load_params(file), names, keep_wheelbase);
  }, "model:");
}

// The parameter values of `names` in a parameter file of `model` (for truth references).
std::vector<double> values_in(const std::string& model, const std::string& file, const std::vector<std::string>& names) {
  return make_spec(model, file, names, false).nominal;
}

py::dict estimate(const std::string& recording, const std::string& model, const std::string& params_file,
                  const std::vector<std::string>& estimate_names, const std::string& estimator, double alm_window_s,
                  bool alm_process, py::object fit, const std::vector<std::string>& measure,
                  const std::map<std::string, double>& meas_std, double param_std, double walk_std,
                  double process_scale, bool keep_wheelbase, const std::string& truth_file, int record_every) {
  using namespace mppi::sysid;
  if (estimator != "alm" && estimator != "ukf")
    throw mppi::Error("estimator: expects alm or ukf, got '" + estimator + "'");
  const VehicleModelSpec spec = make_spec(model, params_file, estimate_names, keep_wheelbase);
  EstimateSettings st;
  st.adaptive = estimator == "alm";
  st.alm_window_s = alm_window_s;
  st.alm_process = alm_process;
  st.measure = measure;
  for (const auto& [c, sd] : meas_std) st.measurement_std.emplace_back(c, sd);
  st.param_initial_std = param_std;
  st.param_walk_std_per_s = walk_std;
  st.process_noise_scale = process_scale;
  st.record_every = record_every;
  if (!fit.is_none()) {
    const auto w = fit.cast<std::pair<double, double>>();
    st.t_begin_s = w.first;
    st.t_end_s = w.second;
  }
  std::string why;
  if (!st.is_valid(&why)) throw mppi::Error("estimate_parameters: " + why);
  const mppi::sysid::PreparedRecording rec = mppi::sysid::prepare(load(recording), recording, 3);
  const std::vector<double> truth =
      truth_file.empty() ? std::vector<double>() : values_in(model, truth_file, spec.estimated);
  EstimateResult res;
  {
    py::gil_scoped_release release;
    res = estimate_parameters(spec, rec, st);
  }
  const std::size_t np = res.names.size(), nk = res.t.size();
  py::dict history, history_std;
  for (std::size_t i = 0; i < np; ++i) {
    DoubleArray h(static_cast<py::ssize_t>(nk)), s(static_cast<py::ssize_t>(nk));
    for (std::size_t k = 0; k < nk; ++k) {
      h.mutable_data()[k] = res.history[k][i];
      s.mutable_data()[k] = res.history_std[k][i];
    }
    history[py::str(res.names[i])] = h;
    history_std[py::str(res.names[i])] = s;
  }
  // Convergence times in s from the fit start, as mppi-fit estimate reports them (inf = never).
  const double t0 = nk ? res.t.front() : 0.0;
  py::dict conv;
  for (double band : {0.05, 0.02}) {
    std::vector<double> to_final(np), to_truth(np, NAN);
    for (std::size_t i = 0; i < np; ++i) {
      to_final[i] = convergence_time(res, i, band) - t0;
      if (!truth.empty()) to_truth[i] = convergence_time_to(res, i, band, truth[i]) - t0;
    }
    const std::string pct = band == 0.05 ? "5pct" : "2pct";
    conv[py::str("final_" + pct)] = to_array(to_final);
    if (!truth.empty()) conv[py::str("truth_" + pct)] = to_array(to_truth);
  }
  py::dict out;
  out["model"] = spec.kind;
  out["names"] = res.names;
  out["nominal"] = to_array(spec.nominal);
  out["initial"] = to_array(res.initial);
  out["estimate"] = to_array(res.final_values);
  out["std"] = to_array(res.final_std);
  out["values"] = [&] {
    py::dict d;
    for (std::size_t i = 0; i < np; ++i) d[py::str(res.names[i])] = res.final_values[i];
    return d;
  }();
  if (!truth.empty()) out["truth"] = to_array(truth);
  out["t"] = to_array(res.t);
  out["history"] = history;
  out["history_std"] = history_std;
  out["convergence_s"] = conv;
  out["measured"] = res.measured;
  out["innovation_rms"] = to_array(res.innovation_rms);
  out["measurement_std"] = to_array(res.measurement_std);
  out["steps"] = res.steps;
  out["projections"] = res.projections;
  out["rejected_steps"] = res.rejected_steps;
  out["wall_s"] = res.wall_s;
  out["yaml"] = spec.to_yaml(res.final_values);
  return out;
}

py::dict validate(const std::string& recording, const std::string& model, const std::string& params_file,
                  const std::map<std::string, double>& values, py::object window, double horizon_s) {
  using namespace mppi::sysid;
  std::vector<std::string> names;
  std::vector<double> v;
  for (const auto& [n, x] : values) names.push_back(n), v.push_back(x);
  const VehicleModelSpec spec = make_spec(model, params_file, names.empty() ? std::vector<std::string>{"mass_kg"} : names, false);
  if (names.empty()) v = spec.nominal;
  const mppi::sysid::PreparedRecording rec = mppi::sysid::prepare(load(recording), recording, 3);
  std::size_t b = 0, e = rec.rows();
  if (!window.is_none()) {
    const auto w = window.cast<std::pair<double, double>>();
    b = row_at_time(rec, w.first);
    e = row_at_time(rec, w.second);
  }
  if (e < b + 2) throw mppi::Error("validate_parameters: fewer than 2 rows in the window");
  ValidationResult r;
  {
    py::gil_scoped_release release;
    r = validate_parameters(spec, v, rec, b, e, horizon_s);
  }
  py::dict simulated, measured;
  for (std::size_t c = 0; c < r.channels.size(); ++c) {
    simulated[py::str(r.channels[c])] = to_array(r.simulated[c]);
    measured[py::str(r.channels[c])] = to_array(r.measured[c]);
  }
  py::dict out;
  out["channels"] = r.channels;
  out["open_loop_rms"] = to_array(r.open_loop_rms);
  out["horizon_rms"] = to_array(r.horizon_rms);
  out["t"] = to_array(r.t);
  out["simulated"] = simulated;
  out["measured"] = measured;
  return out;
}

// ---- the protocol: truth = a parameter file with `overrides` (YAML key names) set ----
py::dict protocol(const std::string& params_file, const std::map<std::string, double>& overrides,
                  const std::string& layout, double manoeuvre_duration_s, double piece_duration_s,
                  double validation_duration_s, double sample_rate_hz, std::uint64_t seed, double noise_scale,
                  const std::string& out_dir) {
  using namespace mppi::sysid;
  const std::string base_file = params_file.empty() ? mppi::sim::data_file("config/autorally_full_vehicle_uncalibrated.yaml") : params_file;
  mppi::FullVehicleParams truth = mppi::load_full_vehicle_params(base_file);
  if (!overrides.empty()) {
    // Set the values through the estimation spec's YAML writer and read them back with the loader.
    std::vector<std::string> names;
    std::vector<double> values;
    for (const auto& [n, x] : overrides) names.push_back(n), values.push_back(x);
    const VehicleModelSpec spec = full_vehicle_spec(truth, names);
    const auto tmp = std::filesystem::temp_directory_path() /
                     ("mppi_py_protocol_" + std::to_string(reinterpret_cast<std::uintptr_t>(&spec)) + ".yaml");
    std::ofstream(tmp) << spec.to_yaml(values);
    try {
      truth = mppi::load_full_vehicle_params(tmp.string());
    } catch (...) {
      std::filesystem::remove(tmp);
      throw;
    }
    std::filesystem::remove(tmp);
  }
  ProtocolOptions o;
  o.layout = parse_protocol_layout(layout);
  o.manoeuvre_duration_s = manoeuvre_duration_s;
  o.piece_duration_s = piece_duration_s;
  o.validation_duration_s = validation_duration_s;
  o.sample_rate_hz = sample_rate_hz;
  o.seed = seed;
  for (double* sd : {&o.position_noise_m, &o.yaw_noise_rad, &o.velocity_noise_mps, &o.rate_noise_radps,
                     &o.angle_noise_rad, &o.accel_noise_mps2, &o.wheel_noise_radps})
    *sd *= noise_scale;
  ProtocolRun run;
  {
    py::gil_scoped_release release;
    run = run_protocol(truth, o);
    if (!out_dir.empty()) write_protocol(run, truth, out_dir);
  }
  py::dict out;
  out["training"] = recording_dict(run.training);
  out["validation"] = recording_dict(run.validation);
  out["truth"] = recording_dict(run.truth);
  return out;
}

// ---- diagnose ----
py::list metrics_list(const std::vector<mppi::diagnose::HorizonMetrics>& ms) {
  py::list l;
  for (const auto& m : ms) {
    py::dict d, rmse, fit;
    for (int c = 0; c < mppi::diagnose::kChannels; ++c) {
      rmse[mppi::diagnose::kChannelNames[c]] = m.rmse[c];
      fit[mppi::diagnose::kChannelNames[c]] = m.fit_percent[c];
    }
    d["horizon_s"] = m.horizon_s;
    d["starts"] = m.starts;
    d["rmse"] = rmse;
    d["fit_percent"] = fit;
    d["position_rmse_m"] = m.position_rmse_m;
    d["normalized_rmse"] = m.normalized_rmse;
    l.append(d);
  }
  return l;
}

py::list params_list(const std::vector<mppi::diagnose::ParamEstimate>& ps) {
  py::list l;
  for (const auto& p : ps) l.append(py::dict(py::arg("name") = p.name, py::arg("value") = p.value,
                                             py::arg("std") = p.stddev, py::arg("unit") = p.unit));
  return l;
}

py::dict diagnose(const std::string& log, const std::string& params, const std::string& holdout,
                  const std::string& validate_log, const std::vector<std::string>& effects, int max_effects,
                  double min_improvement, double min_bic_drop, const std::string& out_dir, bool plots,
                  const std::string& model) {
  using namespace mppi::diagnose;
  DiagnoseOptions o;
  o.holdout = holdout;
  o.out_dir = out_dir;
  o.plots = plots && !out_dir.empty();
  o.selection.candidates = effects;
  o.selection.max_effects = max_effects;
  o.selection.min_val_improvement = min_improvement;
  o.selection.min_bic_drop = min_bic_drop;
  o.params_source = params;
  for (const auto& id : effects) effect_spec(id);  // throws for an unknown id
  const auto nominal = make_model_family(model, params);
  DiagnoseResult r;
  {
    py::gil_scoped_release release;
    PreparedRecording d = load_any(resolve(log));
    if (!validate_log.empty()) {  // fit on log, judge on validate_log (as mppi-fit diagnose --validate)
      const std::size_t first = d.rows();
      d = concat(d, load_any(resolve(validate_log)));
      o.holdout = std::to_string(d.t[first] - 1e-6) + ":" + std::to_string(d.t.back() + 1.0);
    }
    r = run_diagnosis(d, *nominal, o);
  }
  py::list mismatch, candidates;
  for (const auto& m : r.mismatch)
    mismatch.append(py::dict(py::arg("channel") = m.channel, py::arg("where") = m.where,
                             py::arg("magnitude") = m.magnitude, py::arg("rms") = m.rms, py::arg("z") = m.z,
                             py::arg("unit") = m.unit));
  for (const auto& c : r.selection.candidates)
    candidates.append(py::dict(py::arg("id") = c.id, py::arg("joint_of") = c.joint_of, py::arg("params") = params_list(c.params),
                               py::arg("val_improvement") = c.val_improvement, py::arg("bic_delta") = c.bic_delta,
                               py::arg("heldout_improvement") = c.heldout_improvement,
                               py::arg("selected") = c.selected, py::arg("round_selected") = c.round_selected));
  py::dict out;
  out["selected"] = r.selection.selected;
  out["partial"] = r.selection.partial;
  out["ambiguous"] = r.selection.ambiguous;
  out["final_params"] = params_list(r.selection.final_params);
  out["candidates"] = candidates;
  out["mismatch"] = mismatch;
  out["fit_before"] = metrics_list(r.before);
  out["fit_after"] = metrics_list(r.after);
  out["headline_before"] = r.headline_before;
  out["headline_after"] = r.headline_after;
  out["heldout_rmse_reduction"] = r.heldout_rmse_reduction;
  out["model_file"] = r.model_file;
  out["log"] = r.selection.log;
  out["report"] = py::module_::import("json").attr("loads")(r.json);
  return out;
}

}  // namespace

void register_sysid(py::module_& m) {
  using namespace mppi::sysid;

  // ---- real recordings ----
  m.def("load_recording", [](const std::string& spec) { return recording_dict(load(spec)); }, py::arg("spec"),
        "a recording in the project format, or a shipped raw one (DART JetRacer / ETH RC car) converted on the "
        "fly; spec: a path, 'archive.zip:member.csv', or 'real/<file>.zip:<member>' in the data folder. Same "
        "dict as read_recording.");
  m.def("convert_real_recording",
        [](const std::string& spec, const std::string& source, int smoothing_half_window, double cog_offset_m,
           double eth_omega_outlier_radps, const std::string& out_path) {
          RealConvertSettings s;
          s.source = source == "auto" ? RealSource::kAuto
                     : source == "dart" ? RealSource::kDartJetracer
                     : source == "eth"  ? RealSource::kEthRccar
                                        : throw mppi::Error("source: expects auto, dart or eth, got '" + source + "'");
          s.smoothing_half_window = smoothing_half_window;
          s.cog_offset_m = cog_offset_m;
          s.eth_omega_outlier_radps = eth_omega_outlier_radps;
          std::string why;
          if (!s.is_valid(&why)) throw mppi::Error("convert_real_recording: " + why);
          const std::string path = resolve(spec);
          mppi::sim::Recording r;
          {
            py::gil_scoped_release release;
            r = convert_real_file(path, s);
            if (!out_path.empty()) write_recording(r, out_path);
          }
          return recording_dict(r);
        },
        py::arg("spec"), py::arg("source") = "auto", py::arg("smoothing_half_window") = 10,
        py::arg("cog_offset_m") = 0.022, py::arg("eth_omega_outlier_radps") = 20.0, py::arg("out_path") = "",
        "convert a raw real recording (source auto | dart | eth) with explicit settings; writes it to out_path "
        "in the project format when given (as mppi-fit convert)");
  m.def("zip_members", [](const std::string& path) { return zip_members(resolve(path)); }, py::arg("zip_path"),
        "member names of a zip archive");

  // ---- bifilar pendulum ----
  m.def("bifilar_inertia", &bifilar_inertia, py::arg("mass_kg"), py::arg("period_s"), py::arg("r1_m"),
        py::arg("r2_m"), py::arg("height_m"), py::arg("gravity_mps2") = 9.81,
        "I = m g R1 R2 T^2 / (4 pi^2 h)");
  m.def("bifilar_inertia_parallel", &bifilar_inertia_parallel, py::arg("mass_kg"), py::arg("period_s"),
        py::arg("half_separation_m"), py::arg("wire_length_m"), py::arg("gravity_mps2") = 9.81,
        "I = m g b^2 T^2 / (4 pi^2 d)");
  m.def("bifilar_height", &bifilar_height, py::arg("wire_length_m"), py::arg("r1_m"), py::arg("r2_m"),
        "h = sqrt(d^2 - (R1 - R2)^2)");
  m.def("bifilar_period", &bifilar_period, py::arg("inertia_kgm2"), py::arg("mass_kg"), py::arg("r1_m"),
        py::arg("r2_m"), py::arg("height_m"), py::arg("gravity_mps2") = 9.81, "inverse of bifilar_inertia");
  m.def("bifilar_table", [](double g) {
    py::list rows;
    for (const BifilarRow& r : autorally_bifilar_table()) {
      const BifilarCheck c = check_bifilar_row(r, g);
      using namespace pybind11::literals;  // "key"_a = value
      const py::dict d("axis"_a = r.axis, "period_s"_a = r.period_s, "half_separation_m"_a = r.half_separation_m,
                       "wire_length_m"_a = r.wire_length_m, "mass_kg"_a = r.mass_kg,
                       "printed_kgm2"_a = r.printed_kgm2, "computed_kgm2"_a = c.computed_kgm2,
                       "relative_diff"_a = c.relative_diff, "min_kgm2"_a = c.min_kgm2, "max_kgm2"_a = c.max_kgm2,
                       "consistent"_a = c.consistent, "period_for_printed_s"_a = c.period_for_printed_s,
                       "cg_offset_for_printed_m"_a = c.cg_offset_for_printed_m);
      rows.append(d);
    }
    return rows;
  }, py::arg("gravity_mps2") = 9.81,
        "the AutoRally paper's bifilar table with the check of each row: list of dicts (axis, period_s, "
        "half_separation_m, wire_length_m, mass_kg, printed_kgm2, computed_kgm2, relative_diff, min_kgm2, "
        "max_kgm2, consistent, period_for_printed_s, cg_offset_for_printed_m)");

  // ---- simulated estimation protocol ----
  m.def("run_protocol", &protocol, py::arg("params_file") = "", py::arg("overrides") = std::map<std::string, double>{},
        py::arg("layout") = "interleaved", py::arg("manoeuvre_duration_s") = 20.0, py::arg("piece_duration_s") = 4.0,
        py::arg("validation_duration_s") = 13.0, py::arg("sample_rate_hz") = 50.0, py::arg("seed") = 1,
        py::arg("noise_scale") = 1.0, py::arg("out_dir") = "",
        "the paper's estimation protocol driven with the full-vehicle plant (params_file, default "
        "data/config/autorally_full_vehicle_uncalibrated.yaml, the paper's values, with overrides {yaml key: value}); returns {'training', "
        "'validation', 'truth'} recording dicts; out_dir: also writes train.csv, validation.csv, truth.csv, "
        "truth.yaml there (as mppi-fit protocol). Releases the GIL.");

  // ---- estimation ----
  m.def("estimation_param_names", [](const std::string& model) {
    return with_estimable_model(model, []<class E>() { return E::param_names(); }, "model:");
  }, py::arg("model") = mppi::models::SingleTrackModel::kName, "parameter names the model can estimate (mppi-fit estimate --list-params)");
  m.def("estimate_parameters", &estimate, py::arg("recording"), py::arg("model") = mppi::models::SingleTrackModel::kName,
        py::arg("params_file") = "", py::arg("estimate") = std::vector<std::string>{}, py::arg("estimator") = "alm",
        py::arg("alm_window_s") = 10.0, py::arg("alm_process") = false, py::arg("fit") = py::none(),
        py::arg("measure") = std::vector<std::string>{}, py::arg("meas_std") = std::map<std::string, double>{},
        py::arg("param_std") = 0.3, py::arg("walk_std") = 0.003, py::arg("process_scale") = 1.0,
        py::arg("keep_wheelbase") = false, py::arg("truth_file") = "", py::arg("record_every") = 5,
        "joint-state ALM-UKF ('alm') or UKF ('ukf') parameter estimation on a recording (path or "
        "'archive.zip:member'), as mppi-fit estimate with the same defaults. Returns a dict: names, nominal, "
        "initial, estimate, std (arrays in names order), values {name: estimate}, t and history / history_std "
        "{name: array over t}, convergence_s {final_5pct, final_2pct[, truth_5pct, truth_2pct]: arrays, s from "
        "the fit start, inf = never}, measured, innovation_rms, measurement_std, steps, projections, "
        "rejected_steps, wall_s, yaml (the estimated parameter file). Releases the GIL.");
  m.def("validate_parameters", &validate, py::arg("recording"), py::arg("model") = mppi::models::SingleTrackModel::kName,
        py::arg("params_file") = "", py::arg("values") = std::map<std::string, double>{},
        py::arg("window") = py::none(), py::arg("horizon_s") = 1.0,
        "open-loop simulation of the model (params_file with values {name: value} set) over the rows with t in "
        "window (T0, T1) (default: all) with the recorded controls: {channels, open_loop_rms, horizon_rms, t, "
        "simulated {channel: array}, measured {channel: array}}");

  // ---- diagnose ----
  m.def("diagnose", &diagnose, py::arg("log"), py::arg("params") = "", py::arg("holdout") = "0.3",
        py::arg("validate") = "", py::arg("effects") = std::vector<std::string>{}, py::arg("max_effects") = mppi::diagnose::SelectionOptions{}.max_effects,
        py::arg("min_improvement") = 0.03, py::arg("min_bic_drop") = 2.0, py::arg("out_dir") = "",
        py::arg("plots") = true, py::arg("model") = mppi::models::SingleTrackModel::kName,
        "sim-vs-real diagnosis as mppi-fit diagnose: log (recording or raw real one), model (nominal: "
        "single-track, double-track or full-vehicle), params (that model's YAML or a corrected-model file; "
        "'' = library defaults). Returns {selected, final_params, "
        "candidates, mismatch, fit_before, fit_after, headline_before, headline_after, heldout_rmse_reduction, "
        "model_file, log, report (report.json as a dict)}; out_dir: writes the report folder there. Releases "
        "the GIL.");
  m.def("diagnose_synth_open_loop",
        [](const std::string& effects, std::uint64_t seed, double duration_s, double noise_scale,
           const std::string& out_path, const std::string& model) {
          mppi::EffectParams truth;
          const std::vector<std::string> ids = mppi::diagnose::parse_effect_assignments(effects, &truth);
          mppi::diagnose::SensorNoise noise;
          noise.scale = noise_scale;
          mppi::sim::Recording r;
          {
            py::gil_scoped_release release;
            r = mppi::diagnose::synthesize_open_loop(truth, seed, duration_s, noise, model);
            if (!out_path.empty()) write_recording(r, out_path);
          }
          return py::make_tuple(recording_dict(r), ids);
        },
        py::arg("effects") = "", py::arg("seed") = 1, py::arg("duration_s") = 40.0, py::arg("noise_scale") = 1.0,
        py::arg("out_path") = "", py::arg("model") = mppi::models::SingleTrackModel::kName,
        "a fast synthetic recording with hidden effects ('key=value,...', e.g. 'steer_delay_s=0.08'): the "
        "truth plant driven open loop on open ground (the diagnose tests' generator). Returns (recording dict, "
        "effect ids); writes it to out_path when given; model: the truth plant's nominal model.");
}
