// mppi-fit diagnose: sim-vs-real. Locates where a model disagrees with a recording, names the
// missing physics from a library of candidate effects, writes the corrected model and shows
// the held-out fit before and after (docs/DIAGNOSE.md). Sub-commands:
//   mppi-fit diagnose --log FILE [...]     the diagnosis
//   mppi-fit diagnose synth [...]          a synthetic recording with concealed effects
//   mppi-fit diagnose sweep [...]          seeds x effects x sizes: named right / wrong, RMSE
//   mppi-fit diagnose loop [...]           closed loop: MPPI with nominal vs corrected model
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mppi/error.hpp"
#include "dynamics/model_registry.hpp"
#include "mppi_fit_commands.hpp"
#include "sim/closed_loop.hpp"
#include "sim/recording.hpp"
#include "sysid/diagnose/diagnose.hpp"
#include "sysid/diagnose/sweep.hpp"
#include "sysid/diagnose/synth.hpp"

namespace {

using namespace mppi;
using namespace mppi::diagnose;

const char* kUsage = R"(usage:
  mppi-fit diagnose --log FILE [options]         locate, name, model, show (report in --out)
    --log FILE          recording (docs/RECORDING_FORMAT.md)
    --model NAME        nominal model: single-track | double-track | full-vehicle  (single-track)
    --params FILE       nominal parameters: that model's YAML or a corrected-model file
                        (default: the library defaults, e.g. data/config/autorally_single_track.yaml)
    --log may also be a real recording (DART / ETH CSV, or ARCHIVE.zip:MEMBER.csv), converted
                        on the fly (sysid/real_data.hpp)
    --holdout H         held-out fraction at the end (0.3) or time range T0:T1 [s]
    --validate FILE     fit on all of --log, judge on this other recording (replaces --holdout)
    --effects A,B,...   candidate ids (default: all)
    --max-effects N     at most N effects named                              (3)
    --min-improvement F validation-cost reduction an effect must give        (0.03)
    --min-bic-drop B    and BIC decrease                                     (2)
    --out DIR           report.json, report.md, PNG plots, corrected_model.yaml (out/diagnose)
    --no-plots          skip the PNG plots
  mppi-fit diagnose synth --out FILE.csv [--effect key=value,...] [--seed N] [--duration S]
                          [--speed-range MIN:MAX | --speed V] [--samples K] [--track NAME]
                          [--noise-scale F] [--nominal single-track|double-track|full-vehicle]
                          (default: the target speed changes every 2-6 s, uniform in 3:8 m/s;
                          --speed V holds it constant)
  mppi-fit diagnose synth|sweep --generator independent ...   the independent evidence generator
                          (docs/EVIDENCE.md; --generator independent --help lists its options)
  mppi-fit diagnose sweep [--seeds N] [--sizes small,large] [--effects A,B,...] [--clean N]
                          [--duration S] [--speed-range MIN:MAX | --speed V] [--min-bic-drop B]
                          [--nominal MODEL]  (truth base and diagnosed nominal; single-track)
                          [--out DIR]   (seeds 3, clean 4; recordings already in DIR are reused)
  mppi-fit diagnose loop --truth key=value,... | --case ID:small|large  --model-params FILE [--laps N] [--speed V]
                         [--samples K] [--seed N | --seeds N] [--nominal MODEL] [--out DIR]
                         (--seeds N: seeds 1..N and a mean +- sd summary)
Effect ids: aero_drag rolling_resistance steer_delay throttle_delay steer_lag throttle_lag
steer_offset steer_gain tire_saturation friction_change load_transfer motor_voltage_sag road_grade
)";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

double number(const std::string& flag, const std::string& s) {
  try {
    std::size_t used = 0;
    const double v = std::stod(s, &used);
    if (used == s.size()) return v;
  } catch (const std::exception&) {
  }
  throw UsageError(flag + " expects a number, got '" + s + "'");
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

int cmd_diagnose(int argc, char** argv) {
  std::string log, params, validate, model = mppi::models::SingleTrackModel::kName;
  DiagnoseOptions o;
  o.out_dir = "out/diagnose";
  for (int i = 1; i < argc; ++i) {
    const std::string f = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(f + " needs a value");
      return argv[++i];
    };
    if (f == "--log") log = value();
    else if (f == "--model") model = value();
    else if (f == "--params") params = value();
    else if (f == "--holdout") o.holdout = value();
    else if (f == "--validate") validate = value();
    else if (f == "--effects") o.selection.candidates = split_list(value());
    else if (f == "--max-effects") o.selection.max_effects = static_cast<int>(number(f, value()));
    else if (f == "--min-improvement") o.selection.min_val_improvement = number(f, value());
    else if (f == "--min-bic-drop") o.selection.min_bic_drop = number(f, value());
    else if (f == "--out") o.out_dir = value();
    else if (f == "--no-plots") o.plots = false;
    else if (f == "--help" || f == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    } else throw UsageError("unknown option " + f);
  }
  if (log.empty()) throw UsageError("--log FILE is required");
  for (const auto& id : o.selection.candidates) effect_spec(id);  // throws for unknown ids
  const auto nominal = make_model_family(model, params);  // throws for other models, bad files
  o.params_source = params;
  DiagData d = load_any(log);
  if (!validate.empty()) {  // fit on --log, judge on --validate
    const std::size_t first = d.rows();
    d = concat(d, load_any(validate));
    o.holdout = std::to_string(d.t[first] - 1e-6) + ":" + std::to_string(d.t.back() + 1.0);
  }
  const DiagnoseResult r = run_diagnosis(d, *nominal, o);
  std::printf("mismatch (strongest first):\n");
  for (std::size_t i = 0; i < r.mismatch.size() && i < 8; ++i)
    std::printf("  %-9s %-45s %+.3g %s (z %.1f)\n", r.mismatch[i].channel.c_str(), r.mismatch[i].where.c_str(),
                r.mismatch[i].magnitude, r.mismatch[i].unit.c_str(), r.mismatch[i].z);
  std::printf("selected:");
  for (const auto& s : r.selection.selected) std::printf(" %s", s.c_str());
  std::printf("%s\n", r.selection.selected.empty() ? " (none)" : "");
  std::printf("verdict: %s\n", r.selection.verdict.c_str());
  for (const auto& s : r.selection.suspected) std::printf("  suspected %s: %s\n", s.id.c_str(), s.reason.c_str());
  for (const auto& p : r.selection.final_params)
    std::printf("  %s = %.4g +- %.2g %s\n", p.name.c_str(), p.value, p.stddev, p.unit.c_str());
  std::printf("held-out normalised RMSE at 1 s: %.4f -> %.4f (%.1f %% reduction)\nreport: %s/report.md\n",
              r.headline_before, r.headline_after, 100 * r.heldout_rmse_reduction, o.out_dir.c_str());
  return 0;
}

// "--speed-range A:B": the driver's target speed varies in [A, B] m/s.
void speed_range(const std::string& flag, const std::string& text, SynthOptions* o) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) throw UsageError(flag + " expects MIN:MAX, got '" + text + "'");
  o->speed_min_mps = number(flag, text.substr(0, colon));
  o->speed_max_mps = number(flag, text.substr(colon + 1));
  if (!(o->speed_min_mps > 0 && o->speed_max_mps >= o->speed_min_mps))
    throw UsageError(flag + ": need 0 < MIN <= MAX, got '" + text + "'");
  o->vary_speed = true;
}

int cmd_synth(int argc, char** argv) {
  SynthOptions o;
  std::string out;
  for (int i = 2; i < argc; ++i) {
    const std::string f = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(f + " needs a value");
      return argv[++i];
    };
    if (f == "--out") out = value();
    else if (f == "--effect") o.truth_ids = parse_effect_assignments(value(), &o.truth);
    else if (f == "--seed") o.seed = static_cast<std::uint64_t>(number(f, value()));
    else if (f == "--duration") o.duration_s = number(f, value());
    else if (f == "--speed") {
      o.target_speed_mps = number(f, value());
      o.vary_speed = false;
    } else if (f == "--speed-range") speed_range(f, value(), &o);
    else if (f == "--samples") o.samples = static_cast<int>(number(f, value()));
    else if (f == "--track") o.track = value();
    else if (f == "--nominal") o.nominal_model = value();
    else if (f == "--noise-scale") o.noise.scale = number(f, value());
    else throw UsageError("unknown option " + f);
  }
  if (out.empty()) throw UsageError("synth: --out FILE.csv is required");
  o.work_dir = out + ".work";
  const int crashes = synthesize(o, out);
  std::printf("wrote %s (hidden effects: %zu, crashes %d)\n", out.c_str(), o.truth_ids.size(), crashes);
  return 0;
}

int cmd_sweep(int argc, char** argv) {
  int seeds = 3, clean = 4;
  SelectionOptions sel;
  SynthOptions driver;  // the driver's speed (schedule) for every recording
  double duration = 60;
  std::vector<std::string> sizes = {"small", "large"}, effects;
  std::string out = "out/diagnose_sweep";
  for (int i = 2; i < argc; ++i) {
    const std::string f = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(f + " needs a value");
      return argv[++i];
    };
    if (f == "--seeds") seeds = static_cast<int>(number(f, value()));
    else if (f == "--clean") clean = static_cast<int>(number(f, value()));
    else if (f == "--sizes") sizes = split_list(value());
    else if (f == "--effects") effects = split_list(value());
    else if (f == "--duration") duration = number(f, value());
    else if (f == "--out") out = value();
    else if (f == "--min-bic-drop") sel.min_bic_drop = number(f, value());
    else if (f == "--nominal") driver.nominal_model = value();
    else if (f == "--speed") {
      driver.target_speed_mps = number(f, value());
      driver.vary_speed = false;
    } else if (f == "--speed-range") speed_range(f, value(), &driver);
    else throw UsageError("unknown option " + f);
  }
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

int cmd_loop(int argc, char** argv) {
  sim::ClosedLoopConfig base;
  base.plant = "corrected";
  base.laps = 3;
  base.target_speed_mps = 8.0;
  base.controller.num_samples = 1024;
  base.controller.horizon = 100;
  base.progress = false;
  base.actuators.steer_rate_per_s = 1e4f;
  base.actuators.throttle_rate_per_s = 1e4f;
  std::string truth_text, model_params, out = "out/diagnose_loop";
  int seeds = 0;  // 0 = the one --seed
  std::string nominal = mppi::models::SingleTrackModel::kName;  // the plant's base and the nominal controller's model
  for (int i = 2; i < argc; ++i) {
    const std::string f = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(f + " needs a value");
      return argv[++i];
    };
    if (f == "--truth") truth_text = value();
    else if (f == "--case") {  // ID:SIZE, the sweep's hidden effect of that size
      const std::string v = value();
      const auto colon = v.find(':');
      const std::string id = v.substr(0, colon), size = colon == std::string::npos ? "large" : v.substr(colon + 1);
      bool found = false;
      for (const auto& c : sweep_cases())
        if (c.id == id && (size == "small" || size == "large")) {
          truth_text = size == "small" ? c.small : c.large;
          found = true;
        }
      if (!found) throw UsageError("--case: expected EFFECT_ID:small|large, got '" + v + "'");
    } else if (f == "--model-params") model_params = value();
    else if (f == "--laps") base.laps = static_cast<int>(number(f, value()));
    else if (f == "--speed") base.target_speed_mps = number(f, value());
    else if (f == "--samples") base.controller.num_samples = static_cast<int>(number(f, value()));
    else if (f == "--seed") base.controller.seed = static_cast<std::uint64_t>(number(f, value()));
    else if (f == "--seeds") seeds = static_cast<int>(number(f, value()));
    else if (f == "--nominal") nominal = value();
    else if (f == "--track") base.track = value();
    else if (f == "--out") out = value();
    else throw UsageError("unknown option " + f);
  }
  if (model_params.empty()) throw UsageError("loop: --model-params FILE (the corrected model) is required");
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

}  // namespace

bool mppi_fit_wants_independent_generator(int argc, char** argv);  // apps/mppi_fit_evidence.cpp
int mppi_fit_evidence(int argc, char** argv);

int mppi_fit_diagnose(int argc, char** argv) {
  try {
    const std::string sub = argc > 1 ? argv[1] : "";
    if ((sub == "synth" || sub == "sweep") && mppi_fit_wants_independent_generator(argc, argv))
      return mppi_fit_evidence(argc, argv);  // the independent evidence generator (docs/EVIDENCE.md)
    if (sub == "synth") return cmd_synth(argc, argv);
    if (sub == "sweep") return cmd_sweep(argc, argv);
    if (sub == "loop") return cmd_loop(argc, argv);
    return cmd_diagnose(argc, argv);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "mppi-fit diagnose: %s\n%s", e.what(), kUsage);
    return 2;
  } catch (const mppi::Error& e) {
    std::fprintf(stderr, "mppi-fit diagnose: error: %s\n", e.what());
    return 1;
  }
}
