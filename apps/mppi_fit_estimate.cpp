// mppi-fit estimate: joint-state UKF / ALM-UKF parameter estimation from a recording, with
// convergence (CSV + PNG), estimated parameters (YAML for mppi-sim / the controller), and an
// open-loop validation on held-out data against the nominal parameters. docs/ESTIMATION.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli/app.hpp"
#include "cli/options.hpp"
#include "dynamics/vehicle_params.hpp"
#include "dynamics/model_registry.hpp"
#include "base/error.hpp"
#include "mppi_fit_bag.hpp"
#include "mppi_fit_commands.hpp"
#include "sim/data_dir.hpp"
#include "sysid/estimable_models.hpp"
#include "sysid/estimation_plots.hpp"
#include "sysid/observability.hpp"
#include "sysid/real_data.hpp"
#include "sysid/vehicle_estimation.hpp"

namespace {

std::string resolve(const std::string& spec) {
  if (spec.rfind("real/", 0) != 0) return spec;
  const std::size_t z = spec.find(".zip:");
  return z == std::string::npos ? mppi::sim::data_file(spec)
                                : mppi::sim::data_file(spec.substr(0, z + 4)) + spec.substr(z + 4);
}

// What the command line sets.
struct EstimateArgs {
  std::string input, model = mppi::models::SingleTrackModel::kName, params_file, out_dir = "out/estimate",
                     truth_file, val_file, estimator = "alm", fit_text, val_text, estimate_text, measure_text,
                     meas_std_text;
  mppi::sysid::EstimateSettings st;
  bool list_params = false, observe = false, keep_wheelbase = false;
  double horizon_s = 1.0, rank_tol = 1e-7;
};

std::vector<std::string> estimable_params(const std::string& model) {
  return mppi::sysid::with_estimable_model(model, []<class E>() { return E::param_names(); });
}

int run_estimate(EstimateArgs& args) {
  using namespace mppi;
  using namespace mppi::sysid;
  using mppi::cli::usage_error;
  const std::string input = args.input, model = args.model, params_file = args.params_file,
                    out_dir = args.out_dir, truth_file = args.truth_file, val_file = args.val_file;
  EstimateSettings st = args.st;
  const bool observe = args.observe, keep_wheelbase = args.keep_wheelbase;
  const double horizon_s = args.horizon_s, rank_tol = args.rank_tol;
  std::vector<std::string> estimate_names = mppi::cli::split_list(args.estimate_text);
  const bool have_fit = !args.fit_text.empty(), have_val = !args.val_text.empty();
  std::pair<double, double> fit{-1e300, 1e300}, val{0, 0};
  if (have_fit) fit = mppi::cli::parse_number_pair(args.fit_text);
  if (have_val) val = mppi::cli::parse_number_pair(args.val_text);
  st.adaptive = args.estimator == "alm";
  st.measure = mppi::cli::split_list(args.measure_text);
  for (const auto& kv : mppi::cli::split_list(args.meas_std_text)) {
    const std::size_t eq = kv.find('=');
    char* end = nullptr;
    const double sd = eq == std::string::npos ? 0.0 : std::strtod(kv.c_str() + eq + 1, &end);
    if (eq == std::string::npos || end == kv.c_str() + eq + 1 || *end != '\0')
      throw usage_error("--meas-std", "expects COLUMN=STD,..., got '" + kv + "'");
    st.measurement_std.emplace_back(kv.substr(0, eq), sd);
  }
  if (args.list_params) {
    // The estimable parameters, described by the model's parameter table.
    std::fputs(mppi::cli::model_parameter_help(model, estimable_params(model)).c_str(), stdout);
    return 0;
  }
  if (input.empty()) throw usage_error("RECORDING", "no recording given");
  if (have_fit) {
    st.t_begin_s = fit.first;
    st.t_end_s = fit.second;
  }
  std::string why;
  if (!st.is_valid(&why)) throw CLI::ValidationError(why);
  if (!(horizon_s > 0)) throw usage_error("--horizon", "must be > 0");

  try {
    // Model and its base parameters.
    VehicleModelSpec spec, truth_spec;
    bool have_truth = !truth_file.empty();
    with_estimable_model(model, [&]<class E>() {
      const typename E::Params base =
          E::load_params(params_file.empty() ? sim::data_file(E::kEstimationFile) : params_file);
      if (estimate_names.empty()) estimate_names = E::default_estimated();
      spec = E::spec(base, estimate_names, keep_wheelbase);
      if (have_truth) truth_spec = E::spec(E::load_params(truth_file), estimate_names);
    });
    const PreparedRecording rec = prepare(load_any_recording(resolve(input)), input, 3);
    const std::size_t np = spec.estimated.size();
    std::vector<double> truth(np, NAN);
    if (have_truth) truth = truth_spec.nominal;

    if (observe) {
      // Joint-state model [x; p] along the measured trajectory of the fit window (up to 200
      // points), transitions over the sampling interval, measurements = the measured columns.
      const auto& t = rec.column("t");
      std::vector<std::size_t> rows;
      for (std::size_t i = 0; i < rec.rows(); ++i)
        if (t[i] >= st.t_begin_s && t[i] < st.t_end_s) rows.push_back(i);
      if (rows.size() < 3) throw Error("--observability: fewer than 3 rows in the fit window");
      std::vector<int> idx;
      std::vector<std::string> names = spec.state_names;
      for (const auto& [col, i] : spec.measurable)
        if (rec.has_column(col) && (st.measure.empty() || std::find(st.measure.begin(), st.measure.end(), col) != st.measure.end()))
          idx.push_back(i);
      for (const auto& n : spec.estimated) names.push_back(n);
      const int nx = spec.nx;
      TransitionFn F = [&spec, nx, np](const Vec& xa, const Vec& u) -> Vec {
        std::vector<double> v(xa.data() + nx, xa.data() + nx + np);
        Vec out = xa;
        const double uu[2] = {u(0), u(1)};
        spec.step(v, out.data(), uu, u(2));
        return out;
      };
      MeasurementFn H = [idx](const Vec& xa, const Vec&) -> Vec {
        Vec y(static_cast<int>(idx.size()));
        for (std::size_t i = 0; i < idx.size(); ++i) y(i) = xa(idx[i]);
        return y;
      };
      const std::size_t n_pts = std::min<std::size_t>(200, rows.size() - 1);
      const std::size_t start = (rows.size() - 1 - n_pts) / 2;
      std::vector<Vec> xs, us;
      Vec scale(nx + static_cast<int>(np));
      for (int i = 0; i < nx; ++i) scale(i) = 1.0;
      for (std::size_t j = 0; j < np; ++j) scale(nx + j) = std::max(1e-3, std::abs(spec.nominal[j]));
      for (std::size_t k = 0; k < n_pts; ++k) {
        const std::size_t r = rows[start + k];
        Vec xa(nx + static_cast<int>(np));
        spec.init_state(rec, r, xa.data());
        for (std::size_t j = 0; j < np; ++j) xa(nx + j) = spec.nominal[j];
        Vec u(3);
        u << rec.steer_over(r), rec.throttle_over(r), t[r + 1] - t[r];
        xs.push_back(xa);
        us.push_back(u);
      }
      ObservabilitySettings os;
      os.rank_tolerance = rank_tol;
      const ObservabilityReport rep = observability(F, H, xs, us, scale, os);
      std::printf("observability of the joint %s model (%d states + %zu parameters) over %zu samples,"
                  " t %.2f..%.2f s, measured %zu channels:\n%s\n", spec.kind.c_str(), nx, np, n_pts,
                  t[rows[start]], t[rows[start + n_pts - 1]], idx.size(), rep.describe(names).c_str());
      std::printf("smallest singular values:");
      for (int i = std::max(0, static_cast<int>(rep.singular_values.size()) - 5); i < rep.singular_values.size(); ++i)
        std::printf(" %.3g", rep.singular_values(i));
      std::printf("\n");
      return rep.full_rank() ? 0 : 3;
    }

    std::printf("estimating %zu %s parameters with the %s on %s (%zu rows)\n", np, spec.kind.c_str(),
                st.adaptive ? "ALM-UKF" : "joint-state UKF", input.c_str(), rec.rows());
    const EstimateResult res = estimate_parameters(spec, rec, st);
    std::filesystem::create_directories(out_dir);

    // Parameters and convergence.
    {
      std::ofstream y(out_dir + "/estimated.yaml");
      y << "# " << spec.kind << " parameters estimated by mppi-fit estimate (" << (st.adaptive ? "ALM-UKF" : "joint-state UKF")
        << ") from " << input << "\n# estimated: ";
      for (std::size_t i = 0; i < np; ++i) y << (i ? ", " : "") << spec.estimated[i];
      y << "\n" << spec.to_yaml(res.final_values);
      if (!y) throw Error(out_dir + "/estimated.yaml: cannot write");
    }
    // The file must load in the simulator and the controller: parse it back with their loader.
    try {
      with_estimable_model(model, [&]<class E>() { (void)E::load_params(out_dir + "/estimated.yaml"); });
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mppi-fit estimate: WARNING: the estimated parameters do not load: %s\n", e.what());
    }
    {
      std::ofstream c(out_dir + "/convergence.csv");
      c << "t";
      for (const auto& n : res.names) c << "," << n << "," << n << "_std";
      c << "\n";
      for (std::size_t k = 0; k < res.t.size(); ++k) {
        c << res.t[k];
        for (std::size_t i = 0; i < np; ++i) c << "," << res.history[k][i] << "," << res.history_std[k][i];
        c << "\n";
      }
    }
    std::vector<PlotPanel> conv;
    for (std::size_t i = 0; i < np; ++i) {
      PlotPanel p;
      // Convergence time (5% band around the truth if known, else around the final value):
      // in the title and as a red dashed vertical line.
      const double tc = have_truth ? convergence_time_to(res, i, 0.05, truth[i]) : convergence_time(res, i, 0.05);
      {
        char b[64];
        if (std::isfinite(tc))
          std::snprintf(b, sizeof b, "  (5%%: %.1f s)", tc - res.t.front());
        else
          std::snprintf(b, sizeof b, "  (5%%: never)");
        p.title = res.names[i] + b;
      }
      p.x_label = "t [s]";
      PlotSeries s, lo, hi;
      for (std::size_t k = 0; k < res.t.size(); ++k) {
        s.x.push_back(res.t[k]);
        s.y.push_back(res.history[k][i]);
        lo.y.push_back(res.history[k][i] - 2 * res.history_std[k][i]);
        hi.y.push_back(res.history[k][i] + 2 * res.history_std[k][i]);
      }
      lo.x = hi.x = s.x;
      lo.colour = hi.colour = 4;
      lo.dashed = hi.dashed = true;
      s.label = "estimate";
      hi.label = "+-2 sd";
      p.series = {lo, hi, s};
      if (std::isfinite(tc)) {
        const double y0 = *std::min_element(lo.y.begin(), lo.y.end());
        const double y1 = *std::max_element(hi.y.begin(), hi.y.end());
        p.series.push_back({{tc, tc}, {y0, y1}, 3, "", true});
      }
      if (have_truth) p.hlines.push_back(truth[i]);
      conv.push_back(p);
    }
    write_panels_png(out_dir + "/convergence.png",
                     std::string(st.adaptive ? "ALM-UKF" : "joint-state UKF") + " parameter convergence" +
                         (have_truth ? " (grey dashed: true value; red: stays within 5% of it after)"
                                     : " (red: stays within 5% of the final value after)"),
                     conv, 3, 380, 220);

    // Validation: held-out window or recording, estimated vs nominal parameters.
    PreparedRecording val_rec;
    std::size_t vb = 0, ve = 0;
    bool validate = false;
    if (!val_file.empty()) {
      val_rec = prepare(load_any_recording(resolve(val_file)), val_file, 3);
      vb = 0;
      ve = val_rec.rows();
      validate = true;
    } else if (have_val) {
      val_rec = rec;
      vb = row_at_time(rec, val.first);
      ve = row_at_time(rec, val.second);
      validate = ve > vb + 1;
    }
    ValidationResult ve_est, ve_nom;
    if (validate) {
      ve_est = validate_parameters(spec, res.final_values, val_rec, vb, ve, horizon_s);
      ve_nom = validate_parameters(spec, spec.nominal, val_rec, vb, ve, horizon_s);
      std::vector<PlotPanel> panels;
      PlotPanel path;
      path.title = "path (open loop from the first state)";
      path.x_label = "x [m]";
      path.equal_axes = true;
      PlotSeries m{ve_est.measured[0], ve_est.measured[1], 0, "measured"};
      PlotSeries e{ve_est.simulated[0], ve_est.simulated[1], 1, "estimated"};
      PlotSeries n{ve_nom.simulated[0], ve_nom.simulated[1], 4, "nominal", true};
      path.series = {m, n, e};
      panels.push_back(path);
      for (int c : {3, 4, 5, 2}) {
        PlotPanel p;
        p.title = ve_est.channels[c] + " (open loop)";
        p.x_label = "t [s]";
        p.series = {{ve_est.t, ve_est.measured[c], 0, "measured"},
                    {ve_est.t, ve_nom.simulated[c], 4, "nominal", true},
                    {ve_est.t, ve_est.simulated[c], 1, "estimated"}};
        panels.push_back(p);
      }
      write_panels_png(out_dir + "/validation.png", "held-out validation: model with estimated vs nominal parameters",
                       panels, 3, 420, 300);
    }

    // Tables.
    std::ostringstream sum;
    sum << "model " << spec.kind << ", estimator " << (st.adaptive ? "ALM-UKF" : "joint-state UKF") << ", recording "
        << input << "\nfit: " << res.steps << " steps, t " << res.t.front() << ".." << res.t.back() << " s, "
        << res.wall_s << " s wall, PD projections " << res.projections << ", rejected steps " << res.rejected_steps
        << "\nmeasured:";
    for (std::size_t i = 0; i < res.measured.size(); ++i)
      sum << " " << res.measured[i] << " (innovation rms " << res.innovation_rms[i] << ", noise std "
          << res.measurement_std[i] << ")";
    // Convergence time: the last exit from a band around the final estimate and, with --truth,
    // around the true value ("never" when the estimate ends outside it); seconds from the fit start.
    auto conv_text = [](double t) {
      char b[16];
      if (std::isfinite(t)) std::snprintf(b, sizeof b, "%.1f", t);
      else std::snprintf(b, sizeof b, "never");
      return std::string(b);
    };
    sum << "\n\nconvergence: time [s from the fit start] after which the estimate stays within 5% / 2% of its final\n"
        << "value" << (have_truth ? " and of the truth" : "") << "\n";
    sum << "parameter                    initial     estimate    2sd         truth       error%   final 5%/2%  "
        << (have_truth ? "truth 5%/2%" : "") << "\n";
    std::ofstream pc(out_dir + "/parameters.csv");
    pc << "name,initial,estimate,std,truth,error_pct,converged_2pct_s,converged_5pct_s,converged_truth_2pct_s,"
          "converged_truth_5pct_s\n";
    double slowest_final5 = 0, slowest_truth5 = 0;
    std::string slowest_final5_name, slowest_truth5_name;
    for (std::size_t i = 0; i < np; ++i) {
      const double err = have_truth ? 100.0 * (res.final_values[i] - truth[i]) / truth[i] : NAN;
      const double t0 = res.t.front();
      const double c2 = convergence_time(res, i, 0.02) - t0, c5 = convergence_time(res, i, 0.05) - t0;
      const double ct2 = have_truth ? convergence_time_to(res, i, 0.02, truth[i]) - t0 : NAN;
      const double ct5 = have_truth ? convergence_time_to(res, i, 0.05, truth[i]) - t0 : NAN;
      if (c5 >= slowest_final5) slowest_final5 = c5, slowest_final5_name = res.names[i];
      if (have_truth && !(ct5 < slowest_truth5)) slowest_truth5 = ct5, slowest_truth5_name = res.names[i];
      char line[256];
      std::snprintf(line, sizeof line, "%-28s %-11.5g %-11.5g %-11.3g %-11.5g %-8.2f %-12s %s\n", res.names[i].c_str(),
                    res.initial[i], res.final_values[i], 2 * res.final_std[i], truth[i], err,
                    (conv_text(c5) + " / " + conv_text(c2)).c_str(),
                    have_truth ? (conv_text(ct5) + " / " + conv_text(ct2)).c_str() : "");
      sum << line;
      pc << res.names[i] << "," << res.initial[i] << "," << res.final_values[i] << "," << res.final_std[i] << ","
         << truth[i] << "," << err << "," << c2 << "," << c5 << "," << ct2 << "," << ct5 << "\n";
    }
    auto seconds = [&](double t) { return std::isfinite(t) ? conv_text(t) + " s" : std::string("never"); };
    sum << "slowest to settle within 5% of its final value: " << slowest_final5_name << " (" << seconds(slowest_final5)
        << ")\n";
    if (have_truth)
      sum << "slowest to stay within 5% of the truth: " << slowest_truth5_name << " (" << seconds(slowest_truth5)
          << ")\n";
    if (validate) {
      sum << "\nvalidation (" << ve - vb << " rows): rms error, estimated vs nominal parameters\n"
          << "channel     open-loop est   open-loop nom   " << horizon_s << "s-rollouts est   " << horizon_s
          << "s-rollouts nom\n";
      for (std::size_t c = 0; c < ve_est.channels.size(); ++c) {
        char line[200];
        std::snprintf(line, sizeof line, "%-10s  %-14.4g  %-14.4g  %-17.4g  %-14.4g\n", ve_est.channels[c].c_str(),
                      ve_est.open_loop_rms[c], ve_nom.open_loop_rms[c], ve_est.horizon_rms[c], ve_nom.horizon_rms[c]);
        sum << line;
      }
    }
    std::ofstream(out_dir + "/summary.txt") << sum.str();
    std::fputs(sum.str().c_str(), stdout);
    std::printf("wrote %s/{estimated.yaml, convergence.csv, convergence.png, parameters.csv, summary.txt%s}\n",
                out_dir.c_str(), validate ? ", validation.png" : "");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit estimate: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

void add_estimate_command(CLI::App& fit, FitCommands& commands) {
  auto args = std::make_shared<EstimateArgs>();
  mppi::sysid::EstimateSettings& st = args->st;
  CLI::App* cmd = fit.add_subcommand(
      "estimate", "estimate model parameters from a recording (UKF, joint UKF, ALM-UKF); docs/ESTIMATION.md");
  cmd->add_option("recording", args->input,
                  "a recording (docs/RECORDING_FORMAT.md), or a shipped raw one converted on the fly: "
                  "real/dart_jetracer.zip:<member>.csv (see mppi-fit convert --list), or a rosbag FILE.bag (docs/ROSBAG.md)")
      ->type_name("RECORDING");
  add_bag_options(cmd);
  mppi::cli::add_model_option(*cmd, "--model", args->model, "model", mppi::sysid::estimable_model_names());
  cmd->add_option("--params", args->params_file,
                  "base parameters (YAML of that model, keys in --list-params; default "
                  "data/config/autorally_<model>.yaml; the full vehicle: autorally_full_vehicle_uncalibrated.yaml, the paper's values)")
      ->type_name("FILE");
  cmd->add_option("--estimate", args->estimate_text, "parameters to estimate (YAML keys, tyre.B etc.; default: a "
                                                     "model's usual set)")
      ->type_name("A,B,...");
  cmd->add_flag("--list-params", args->list_params,
                "print the estimable parameters of the model (from its parameter table) and exit");
  cmd->add_option("--estimator", args->estimator, "alm (ALM-UKF) | ukf (standard joint-state UKF)")
      ->type_name("NAME")
      ->check(CLI::IsMember({"alm", "ukf"}).description(""));
  cmd->add_option("--alm-window", st.alm_window_s, "noise samples from the last S seconds")->type_name("S");
  cmd->add_flag("--alm-process", st.alm_process, "also re-estimate Q (off: Q and R together drift, see docs)");
  cmd->add_option("--fit", args->fit_text, "fit on rows with t in [T0, T1) s (default all)")
      ->type_name("T0:T1")
      ->check(mppi::cli::number_pair());
  cmd->add_option("--validate", args->val_text, "held-out rows of the same recording for validation")
      ->type_name("T0:T1")
      ->check(mppi::cli::number_pair());
  cmd->add_option("--validate-recording", args->val_file, "held-out recording (instead of a window)")
      ->type_name("FILE");
  cmd->add_option("--horizon", args->horizon_s, "validation rollouts restarted every S seconds")->type_name("S");
  cmd->add_option("--measure", args->measure_text,
                  "recording columns used as measurements (default: all the model has)")
      ->type_name("A,B,...");
  cmd->add_option("--meas-std", args->meas_std_text, "measurement noise std overrides (initial R for the ALM)")
      ->type_name("C=SD,...");
  cmd->add_option("--param-std", st.param_initial_std, "initial std of log(parameter) (linear ones: absolute)")
      ->type_name("F");
  cmd->add_option("--walk-std", st.param_walk_std_per_s, "parameter random walk per sqrt(s), rescaled each step")
      ->type_name("F");
  cmd->add_option("--process-scale", st.process_noise_scale, "scale of the model's process noise")->type_name("F");
  cmd->add_flag("--keep-wheelbase", args->keep_wheelbase, "estimating cg_to_front_axle_m moves the CG, wheelbase fixed");
  cmd->add_option("--truth", args->truth_file, "true parameters (simulated data): report each parameter's error")
      ->type_name("FILE");
  cmd->add_flag("--observability", args->observe, "print the observability check of the joint-state model and exit");
  cmd->add_option("--rank-tol", args->rank_tol, "singular values below F x the largest count as zero")
      ->type_name("F");
  mppi::cli::add_out_option(*cmd, args->out_dir,
                            "estimated.yaml, convergence.csv/.png, validation.png, parameters.csv, summary.txt");
  cmd->footer(mppi::cli::model_parameter_help(mppi::models::SingleTrackModel::kName,
                                              estimable_params(mppi::models::SingleTrackModel::kName)) +
              "(another model's: --list-params --model NAME)");
  commands.add(cmd, [args] { return run_estimate(*args); });
}
