// mppi-fit diagnose: sim-vs-real. Locates where a model disagrees with a recording, names the
// missing physics from a library of candidate effects, writes the corrected model and shows
// the held-out fit before and after (docs/DIAGNOSE.md). Sub-commands:
//   mppi-fit diagnose --log FILE [...]     the diagnosis
//   mppi-fit diagnose synth [...]          a synthetic recording with concealed effects
//   mppi-fit diagnose sweep [...]          seeds x effects x sizes: named right / wrong, RMSE
//   mppi-fit diagnose loop [...]           closed loop: MPPI with nominal vs corrected model
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli/app.hpp"
#include "cli/options.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/effects.hpp"
#include "base/error.hpp"
#include "dynamics/model_registry.hpp"
#include "mppi_fit_bag.hpp"
#include "mppi_fit_commands.hpp"
#include "diagnose/diagnose.hpp"
#include "diagnose/sweep.hpp"
#include "diagnose/synth.hpp"
#include "sim/closed_loop.hpp"
#include "sim/recording.hpp"

namespace {

using namespace mppi;
using namespace mppi::diagnose;

using mppi::cli::split_list;
using mppi::cli::usage_error;

// The nominal models that have an effects version (a corrected model).
std::vector<std::string> nominal_models() {
  std::vector<std::string> names;
  for_each_type(CorrectedNominalModels{}, [&]<class D>() { names.emplace_back(D::kName); });
  return names;
}

// "Effect ids: aero_drag rolling_resistance ...": from the effect table.
std::string effect_ids_help() {
  std::string out = "Effect ids:";
  for (const EffectSpec& e : effect_library()) out += " " + e.id + (e.default_candidate ? "" : " (by name only)");
  return out;
}

// The driver's speed: --speed V holds it constant, --speed-range MIN:MAX varies it.
void add_driver_speed_options(CLI::App& cmd, SynthOptions& o) {
  CLI::Option* speed = cmd.add_option_function<double>(
                              "--speed",
                              [&o](double v) {
                                o.target_speed_mps = v;
                                o.vary_speed = false;
                              },
                              "constant target speed [m/s]")
                           ->type_name("V");
  cmd.add_option_function<std::string>(
         "--speed-range",
         [&o](const std::string& text) {
           const auto [lo, hi] = mppi::cli::parse_number_pair(text);
           if (!(lo > 0 && hi >= lo)) throw usage_error("--speed-range", "need 0 < MIN <= MAX, got '" + text + "'");
           o.speed_min_mps = lo;
           o.speed_max_mps = hi;
           o.vary_speed = true;
         },
         "the target speed changes every 2-6 s, uniform in [MIN, MAX] m/s (default 3:8)")
      ->type_name("MIN:MAX")
      ->check(mppi::cli::number_pair("MIN:MAX"))
      ->excludes(speed);
}

struct DiagnoseArgs {
  std::vector<std::string> logs, validates, tests;
  double test_fraction = 0.0;
  std::string params, model = mppi::models::SingleTrackModel::kName, effects;
  DiagnoseOptions o;
  bool no_plots = false, quiet = false;
  DiagnoseArgs() { o.out_dir = "out/diagnose"; }
};

int cmd_diagnose(DiagnoseArgs& args) {
  const std::string &params = args.params, &model = args.model;
  DiagnoseOptions o = args.o;
  o.selection.candidates = split_list(args.effects);
  o.plots = !args.no_plots;
  if (!args.quiet) {  // the selection takes minutes: its log as it is written, with the elapsed time
    const auto start = std::chrono::steady_clock::now();
    o.selection.progress = [start](const std::string& line) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr, "[%6.1f s] %s\n", s, line.c_str());
    };
  }
  if (args.logs.empty()) throw usage_error("--log", "a recording (--log FILE) is required");
  for (const auto& id : o.selection.candidates) effect_spec(id);  // throws for unknown ids
  const auto nominal = make_model_family(model, params);  // throws for other models, bad files
  o.params_source = params;
  // Several recordings are fitted jointly (concatenated as separate pieces); every --validate
  // recording is held out and scored on its own.
  PreparedRecording d = load_any(args.logs[0]);
  for (std::size_t i = 1; i < args.logs.size(); ++i) d = concat(d, load_any(args.logs[i]));
  // The test data: the end of --log cut off before anything else sees it, and/or --test files.
  std::optional<PreparedRecording> test;
  std::string test_name;
  if (args.test_fraction > 0) {
    const auto cut = static_cast<std::size_t>(std::lround(static_cast<double>(d.rows()) * (1.0 - args.test_fraction)));
    char name[160];
    std::snprintf(name, sizeof name, "the last %.0f %% of --log, t >= %.1f s", 100 * args.test_fraction, d.t[cut]);
    test = slice_rows(d, cut, d.rows());
    d = slice_rows(d, 0, cut);
    test_name = name;
  }
  for (const auto& f : args.tests) {
    const PreparedRecording t = load_any(f);
    test = test ? concat(*test, t) : t;
    test_name += (test_name.empty() ? "" : " + ") + f;
  }
  if (test) {
    o.test = &*test;
    o.test_name = test_name;
  }
  if (!args.validates.empty()) {  // fit on --log, judge on --validate
    const double first_t = d.t.back() + 5.0;  // concat leaves a 10 s gap before the next recording
    for (const auto& v : args.validates) {
      const std::size_t first = d.rows();
      d = concat(d, load_any(v));
      o.heldout_recordings.push_back({v, d.t[first] - 1e-6, d.t.back() + 1e-6});
    }
    o.holdout = std::to_string(first_t) + ":" + std::to_string(d.t.back() + 1.0);
  }
  const DiagnoseResult r = run_diagnosis(d, *nominal, o);
  std::printf("mismatch (strongest first):\n");
  for (std::size_t i = 0; i < r.mismatch.size() && i < 8; ++i)
    std::printf("  %-9s %-45s %+.3g %s (z %.1f)\n", r.mismatch[i].channel.c_str(), r.mismatch[i].where.c_str(),
                r.mismatch[i].magnitude, r.mismatch[i].unit.c_str(), r.mismatch[i].z);
  std::printf("selected:");
  for (const auto& s : r.selection.selected) std::printf(" %s", s.c_str());
  std::printf("%s\n", r.selection.selected.empty() ? " (none)" : "");
  if (!r.selection.partial.empty()) {
    std::printf("partial correction (not named: a mismatch remains that none explains%s%s):",
                r.selection.ambiguous.empty() ? "" : ", or ambiguous: ", r.selection.ambiguous.c_str());
    for (const auto& s : r.selection.partial) std::printf(" %s", s.c_str());
    std::printf("\n");
  }
  std::printf("verdict: %s\n", r.selection.verdict.c_str());
  std::printf("unexplained mismatch: %s\n", mppi::diagnose::unexplained_summary(r.unexplained).c_str());
  for (const auto& s : r.selection.suspected) std::printf("  suspected %s: %s\n", s.id.c_str(), s.reason.c_str());
  for (const auto& p : r.selection.final_params)
    std::printf("  %s = %.4g +- %.2g %s\n", p.name.c_str(), p.value, p.stddev, p.unit.c_str());
  for (const auto& p : r.per_recording)
    std::printf("  held out %s: %.4f -> %.4f\n", p.name.c_str(), p.before, p.after);
  std::printf("held-out normalised RMSE at 1 s: %.4f -> %.4f (%.1f %% reduction)\n", r.headline_before,
              r.headline_after, 100 * r.heldout_rmse_reduction);
  if (test)
    std::printf("headline, test (%s; never seen by the fit or the validation): %.4f -> %.4f (%.1f %% reduction)%s\n",
                test_name.c_str(), r.test.headline_nominal, r.test.headline_corrected, 100 * r.test.reduction,
                r.selection.reliable ? "" : "; not written");
  std::printf("report: %s/report.md\n", o.out_dir.c_str());
  return 0;
}

struct SynthArgs {
  SynthOptions o;
  std::string out, effect;
  double noise_scale = 1.0;
};

int cmd_synth(SynthArgs& args) {
  SynthOptions o = args.o;
  const std::string& out = args.out;
  if (!args.effect.empty()) o.truth_ids = parse_effect_assignments(args.effect, &o.truth);
  o.noise.scale = args.noise_scale;
  if (out.empty()) throw usage_error("--out", "the recording to write (--out FILE.csv) is required");
  o.work_dir = out + ".work";
  const int crashes = synthesize(o, out);
  std::printf("wrote %s (hidden effects: %zu, crashes %d)\n", out.c_str(), o.truth_ids.size(), crashes);
  return 0;
}

struct SweepArgs {
  int seeds = 3, clean = 4;
  SelectionOptions sel;
  SynthOptions driver;  // the driver's speed (schedule) for every recording
  double duration = 60;
  std::string sizes = "small,large", effects, out = "out/diagnose_sweep";
};

int cmd_sweep(SweepArgs& args) {
  const int seeds = args.seeds, clean = args.clean;
  const SelectionOptions& sel = args.sel;
  const SynthOptions& driver = args.driver;
  const double duration = args.duration;
  const std::vector<std::string> sizes = split_list(args.sizes), effects = split_list(args.effects);
  const std::string& out = args.out;
  for (const auto& id : effects) effect_spec(id);  // throws for unknown ids
  std::filesystem::create_directories(out);
  std::ofstream jsonl(out + "/runs.jsonl");
  std::vector<SweepRun> runs;
  auto run_one = [&](const std::string& id, const std::string& size, const std::string& assign, int seed) {
    SynthOptions so = driver;
    so.seed = static_cast<std::uint64_t>(seed);
    so.duration_s = duration;
    if (!assign.empty()) so.truth_ids = parse_effect_assignments(assign, &so.truth);
    const std::string label = id.empty() ? "none" : id;
    const std::string name = label + "_" + size + "_s" + std::to_string(seed);
    so.work_dir = out + "/work/" + name;
    DiagnoseOptions o;
    o.plots = false;
    o.selection = sel;
    const SweepRun r = run_sweep_case(so, out + "/" + name + ".csv", o, label, size);
    std::string named;
    for (const auto& s : r.named) named += (named.empty() ? "" : "+") + s;
    std::printf("%-18s %-5s seed %3d  named %-28s right %d wrong %d  1-s RMSE reduction %5.1f %% "
                "(recording %5.1f %%, truth model %5.1f %%)\n",
                label.c_str(), size.c_str(), seed, named.empty() ? "-" : named.c_str(), r.right, r.wrong,
                100 * r.reduction_clean(), 100 * r.reduction_measured(),
                r.before.measured > 0 ? 100 * (1 - r.truth_model.measured / r.before.measured) : 0.0);
    std::fflush(stdout);
    jsonl << sweep_run_json(r) << "\n" << std::flush;
    runs.push_back(r);
  };
  for (const auto& c : sweep_cases()) {
    if (!effects.empty() && std::find(effects.begin(), effects.end(), c.id) == effects.end()) continue;
    for (const auto& size : sizes)
      for (int s = 1; s <= seeds; ++s) run_one(c.id, size, size == "small" ? c.small : c.large, s);
  }
  for (int s = 1; s <= clean; ++s) run_one("", "clean", "", 100 + s);
  const std::string md = sweep_summary_markdown(runs);
  std::printf("\n%s", md.c_str());
  std::ofstream(out + "/sweep.md") << md;
  std::printf("per-run metrics: %s/runs.jsonl\n", out.c_str());
  return 0;
}

struct LoopArgs {
  sim::ClosedLoopConfig base = defaults();
  std::string truth_text, case_text, model_params, out = "out/diagnose_loop";
  int seeds = 0;  // 0 = the one --seed
  std::string nominal = mppi::models::SingleTrackModel::kName;  // the plant's base and the nominal controller's model

  static sim::ClosedLoopConfig defaults() {
    sim::ClosedLoopConfig base;
    base.plant = "corrected";
    base.laps = 3;
    base.target_speed_mps = 8.0;
    base.controller.num_samples = 1024;
    base.controller.horizon = 100;
    base.progress = false;
    base.actuators.steer_rate_per_s = 1e4f;
    base.actuators.throttle_rate_per_s = 1e4f;
    return base;
  }
};

int cmd_loop(LoopArgs& args) {
  sim::ClosedLoopConfig base = args.base;
  std::string truth_text = args.truth_text;
  const std::string &model_params = args.model_params, &out = args.out, &nominal = args.nominal;
  const int seeds = args.seeds;
  if (!args.case_text.empty()) {  // ID:SIZE, the sweep's hidden effect of that size
    const std::string& v = args.case_text;
    const auto colon = v.find(':');
    const std::string id = v.substr(0, colon), size = colon == std::string::npos ? "large" : v.substr(colon + 1);
    bool found = false;
    for (const auto& c : sweep_cases())
      if (c.id == id && (size == "small" || size == "large")) {
        truth_text = size == "small" ? c.small : c.large;
        found = true;
      }
    if (!found) throw usage_error("--case", "expected EFFECT_ID:small|large, got '" + v + "'");
  }
  if (model_params.empty()) throw usage_error("--model-params", "the corrected model (--model-params FILE) is required");
  std::filesystem::create_directories(out);
  CorrectedModelFile truth;
  truth.selected = parse_effect_assignments(truth_text, &truth.effects);
  truth.nominal_model = nominal;
  make_model_family(nominal);  // throws for a model that has no effects version
  base.plant_params_yaml = out + "/truth_model.yaml";
  std::ofstream(base.plant_params_yaml) << corrected_model_to_yaml(truth, "truth plant of mppi-fit diagnose loop");
  std::vector<std::uint64_t> seed_list;
  if (seeds > 0)
    for (int s = 1; s <= seeds; ++s) seed_list.push_back(static_cast<std::uint64_t>(s));
  else
    seed_list.push_back(base.controller.seed);
  struct Totals {
    std::vector<double> time_s, speed_err;
    int crashes = 0, laps = 0;
  } totals[2];
  std::printf("| seed | controller model | laps | lap times [s] | crashes | mean speed [m/s] | mean |v - v_target| [m/s] |\n"
              "|---|---|---|---|---|---|---|\n");
  for (const std::uint64_t seed : seed_list)
    for (int which = 0; which < 2; ++which) {
      const std::string model = which == 0 ? nominal : "corrected";
      sim::ClosedLoopConfig c = base;
      c.model = model;
      c.controller.seed = seed;
      if (model == "corrected") c.model_params_yaml = model_params;
      c.out_dir = out + "/" + model + (seed_list.size() > 1 ? "_s" + std::to_string(seed) : "");
      const sim::RunSummary s = sim::run_closed_loop(c);
      const sim::Recording rec = sim::RecordingReader::read(c.out_dir + "/log.csv");
      double err = 0;
      const auto& vx = rec.column("vx");
      const auto& vy = rec.column("vy");
      for (std::size_t k = 0; k < rec.rows(); ++k) err += std::abs(std::hypot(vx[k], vy[k]) - c.target_speed_mps);
      std::string laps;
      double total = 0;
      for (double t : s.lap_times_s) {
        char b[16];
        std::snprintf(b, sizeof b, "%s%.2f", laps.empty() ? "" : ", ", t);
        laps += b;
        total += t;
      }
      const double mean_err = rec.rows() ? err / static_cast<double>(rec.rows()) : 0.0;
      std::printf("| %llu | %s | %d/%d | %s | %d | %.2f | %.2f |\n", static_cast<unsigned long long>(seed),
                  which == 0 ? ("nominal " + nominal).c_str() : "corrected (nominal + effects)", s.laps_completed, c.laps,
                  laps.c_str(), s.crashes, s.mean_speed_mps, mean_err);
      std::fflush(stdout);
      Totals& t = totals[which];
      t.crashes += s.crashes;
      t.laps += s.laps_completed;
      if (s.laps_completed == c.laps) t.time_s.push_back(total);
      t.speed_err.push_back(mean_err);
    }
  if (seed_list.size() > 1) {
    auto mean_sd = [](const std::vector<double>& v) {
      if (v.empty()) return std::string("-");
      double m = 0, m2 = 0;
      for (double x : v) m += x;
      m /= static_cast<double>(v.size());
      for (double x : v) m2 += (x - m) * (x - m);
      char b[48];
      std::snprintf(b, sizeof b, "%.2f +- %.2f", m, v.size() > 1 ? std::sqrt(m2 / static_cast<double>(v.size() - 1)) : 0.0);
      return std::string(b);
    };
    std::printf("\n| controller model | seeds finishing all laps | %d-lap time [s] | crashes | mean |v - v_target| [m/s] |\n"
                "|---|---|---|---|---|\n", base.laps);
    for (int which = 0; which < 2; ++which)
      std::printf("| %s | %zu/%zu | %s | %d | %s |\n", which == 0 ? ("nominal " + nominal).c_str() : "corrected",
                  totals[which].time_s.size(), seed_list.size(), mean_sd(totals[which].time_s).c_str(),
                  totals[which].crashes, mean_sd(totals[which].speed_err).c_str());
  }
  return 0;
}

// A command's run: mppi::Error (bad data, bad effect ids) exits 1 with the message.
template <class Args>
std::function<int()> guarded(std::shared_ptr<Args> args, int (*run)(Args&)) {
  return [args, run] {
    try {
      return run(*args);
    } catch (const mppi::Error& e) {
      std::fprintf(stderr, "mppi-fit diagnose: error: %s\n", e.what());
      return 1;
    }
  };
}

// The stability selection's settings, shared by diagnose and its sweep.
void add_stability_options(CLI::App& cmd, SelectionOptions& selection) {
  cmd.add_option("--stability-resamples", selection.stability_resamples,
                 "block-bootstrap resamples of the fit data for stability selection (more: finer inclusion frequencies, "
                 "longer run; 0: off)")
      ->type_name("N")
      ->check(CLI::Range(0, 200));
  cmd.add_option("--min-inclusion", selection.min_inclusion_frequency,
                 "share of the resamples that must choose an effect before it is named")
      ->type_name("F")
      ->check(CLI::Range(0.0, 1.0));
}

void add_diagnose_options(CLI::App& cmd, DiagnoseArgs& a) {
  cmd.add_option("--log", a.logs,
                 "recording (docs/RECORDING_FORMAT.md), or a real recording (DART / ETH CSV, or "
                 "ARCHIVE.zip:MEMBER.csv), or a rosbag FILE.bag (docs/ROSBAG.md), converted on the fly "
                 "(sysid/real_data.hpp); repeat to fit several jointly")
      ->type_name("FILE");
  mppi::cli::add_model_option(cmd, "--model", a.model, "nominal model", nominal_models());
  cmd.add_option("--params", a.params,
                 "nominal parameters: that model's YAML (keys: mppi-sim --list-models) or a corrected-model file "
                 "(default: the model's built-in defaults, listed by mppi-sim --list-models; these are not the shipped "
                 "data/config files: pass --params data/config/autorally_single_track.yaml for the simulator's default plant)")
      ->type_name("FILE");
  cmd.add_option("--holdout", a.o.holdout, "held-out fraction at the end, or time range T0:T1 [s]")->type_name("H");
  cmd.add_option("--test", a.tests,
                 "score the correction afterwards on this recording, which neither the fit nor the validation sees "
                 "(repeat to pool several)")
      ->type_name("FILE");
  cmd.add_option("--test-fraction", a.test_fraction,
                 "cut this fraction off the end of --log first and score the correction on it afterwards (fit, "
                 "validation and test split three ways)")
      ->type_name("F")
      ->check(CLI::Range(0.0, 0.9));
  cmd.add_option("--validate", a.validates,
                 "fit on all of --log, judge on this other recording (replaces --holdout); repeat for a cross-recording table")
      ->type_name("FILE");
  cmd.add_option("--effects", a.effects, "candidate effect ids (default: all)")->type_name("A,B,...");
  cmd.add_option("--max-effects", a.o.selection.max_effects, "at most N selection rounds (a joint candidate such as steer_gain+steer_offset is one)")->type_name("N");
  cmd.add_option("--min-improvement", a.o.selection.min_val_improvement,
                 "validation-cost reduction an effect must give")
      ->type_name("F");
  cmd.add_option("--min-bic-drop", a.o.selection.min_bic_drop, "and BIC decrease")->type_name("B");
  add_stability_options(cmd, a.o.selection);
  cmd.add_option("--max-body-slip", a.o.control_loss.max_body_slip_deg,
                 "rows whose body slip exceeds this (a spin), and 0.5 s around, are left out of the fits (0: none)")
      ->type_name("DEG")
      ->check(CLI::Range(0.0, 90.0));
  mppi::cli::add_out_option(cmd, a.o.out_dir, "report.json, report.md, PNG plots, corrected_model.yaml");
  cmd.add_flag("--no-plots", a.no_plots, "skip the PNG plots");
  cmd.add_flag("--quiet", a.quiet, "no progress on stderr (the selection log as it is written)");
}

// `--generator independent` is taken before parsing (apps/mppi_fit.cpp): listed here for --help.
void add_generator_note(CLI::App& cmd) {
  cmd.add_option_function<std::string>(
         "--generator", [](const std::string&) { throw CLI::ValidationError("--generator", "only 'independent'"); },
         "independent: the independent evidence generator, with its own options (docs/EVIDENCE.md; "
         "--generator independent --help lists them)")
      ->type_name("NAME");
}

void add_synth_options(CLI::App& cmd, SynthArgs& a) {
  add_generator_note(cmd);
  cmd.add_option("--out", a.out, "the recording to write (required)")->type_name("FILE.csv");
  cmd.add_option("--effect", a.effect, "hidden effects and their values")->type_name("key=value,...");
  mppi::cli::add_seed_option(cmd, a.o.seed, "MPPI and noise seed");
  cmd.add_option("--duration", a.o.duration_s, "recording length [s]")->type_name("S");
  add_driver_speed_options(cmd, a.o);
  cmd.add_option("--samples", a.o.samples, "MPPI samples")->type_name("K");
  mppi::cli::add_track_option(cmd, a.o.track);
  cmd.add_option("--noise-scale", a.noise_scale, "scale of the sensor noise")->type_name("F");
  mppi::cli::add_model_option(cmd, "--nominal", a.o.nominal_model, "the truth's base model", nominal_models());
}

void add_sweep_options(CLI::App& cmd, SweepArgs& a) {
  add_generator_note(cmd);
  cmd.add_option("--seeds", a.seeds, "seeds per effect and size")->type_name("N");
  cmd.add_option("--sizes", a.sizes, "effect sizes")->type_name("small,large");
  cmd.add_option("--effects", a.effects, "effect ids (default: all the sweep's cases)")->type_name("A,B,...");
  cmd.add_option("--clean", a.clean, "recordings without a hidden effect")->type_name("N");
  cmd.add_option("--duration", a.duration, "recording length [s]")->type_name("S");
  add_driver_speed_options(cmd, a.driver);
  cmd.add_option("--min-bic-drop", a.sel.min_bic_drop, "BIC decrease an effect must give")->type_name("B");
  add_stability_options(cmd, a.sel);
  mppi::cli::add_model_option(cmd, "--nominal", a.driver.nominal_model, "truth base and diagnosed nominal",
                              nominal_models());
  mppi::cli::add_out_option(cmd, a.out, "recordings, runs.jsonl, sweep.md (recordings already there are reused)");
}

void add_loop_options(CLI::App& cmd, LoopArgs& a) {
  CLI::Option* truth = cmd.add_option("--truth", a.truth_text, "the plant's hidden effects")->type_name("key=value,...");
  cmd.add_option("--case", a.case_text, "the sweep's hidden effect of that size")
      ->type_name("ID:small|large")
      ->excludes(truth);
  cmd.add_option("--model-params", a.model_params, "the corrected model (required)")->type_name("FILE");
  cmd.add_option("--laps", a.base.laps, "laps per run")->type_name("N");
  cmd.add_option("--speed", a.base.target_speed_mps, "target speed [m/s]")->type_name("V");
  cmd.add_option("--samples", a.base.controller.num_samples, "MPPI samples")->type_name("K");
  mppi::cli::add_seed_option(cmd, a.base.controller.seed);
  cmd.add_option("--seeds", a.seeds, "seeds 1..N and a mean +- sd summary (0: the one --seed)")->type_name("N");
  mppi::cli::add_model_option(cmd, "--nominal", a.nominal, "the plant's base and the nominal controller's model",
                              nominal_models());
  mppi::cli::add_track_option(cmd, a.base.track);
  mppi::cli::add_out_option(cmd, a.out, "one folder per run");
}

}  // namespace

void add_diagnose_command(CLI::App& fit, FitCommands& commands) {
  CLI::App* diag = fit.add_subcommand(
      "diagnose", "compare a recording against the simulator's prediction (sim vs real): locate, name, model, show");
  diag->require_subcommand(0, 1);
  diag->footer(effect_ids_help());
  auto diagnose = std::make_shared<DiagnoseArgs>();
  add_diagnose_options(*diag, *diagnose);
  add_bag_options(diag);
  commands.add(diag, guarded(diagnose, &cmd_diagnose));

  auto synth = std::make_shared<SynthArgs>();
  CLI::App* synth_cmd = diag->add_subcommand("synth", "a synthetic recording with concealed effects");
  synth_cmd->footer(effect_ids_help());
  add_synth_options(*synth_cmd, *synth);
  commands.add(synth_cmd, guarded(synth, &cmd_synth));

  auto sweep = std::make_shared<SweepArgs>();
  CLI::App* sweep_cmd = diag->add_subcommand("sweep", "seeds x effects x sizes: effects named right / wrong, RMSE");
  add_sweep_options(*sweep_cmd, *sweep);
  commands.add(sweep_cmd, guarded(sweep, &cmd_sweep));

  auto loop = std::make_shared<LoopArgs>();
  CLI::App* loop_cmd = diag->add_subcommand("loop", "closed loop: MPPI with the nominal vs the corrected model");
  add_loop_options(*loop_cmd, *loop);
  commands.add(loop_cmd, guarded(loop, &cmd_loop));
}
