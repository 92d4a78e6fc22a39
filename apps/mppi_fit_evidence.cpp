// mppi-fit diagnose synth|sweep --generator independent: recordings of the independent evidence
// generator (evidence/, docs/EVIDENCE.md) and the diagnosis judged on them.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "base/error.hpp"
#include "diagnose/evidence_sweep.hpp"
#include "evidence/generator.hpp"

namespace {

using namespace mppi;

const char* kEvidenceUsage = R"(usage:
  mppi-fit diagnose synth --generator independent --out FILE.csv [--effect key=value,...] [--seed N]
        [--duration S] [--track gazebo|marietta|ccrf] [--direction ccw|cw] [--driver pursuit|human]
        [--speed-range MIN:MAX] [--noise-scale F] [--glitch-rate P] [--drop-rate P] [--vehicle FILE.yaml]
        [--rate HZ]  (the driver's and the log's rate, default 50)
        writes FILE.csv, FILE.clean.csv (noise-free), FILE.truth.json (effects, sizes, table ids);
        the car has the constants of --vehicle (default data/config/autorally_single_track.yaml):
        diagnose against the same file (mppi-fit diagnose --params FILE.yaml)
  mppi-fit diagnose sweep --generator independent [--reduced] [--seeds N] [--sizes small,large]
        [--effects A,B] [--pairs N] [--clean N] [--duration S] [--jobs N] [--out DIR] [--md FILE]
        [--vehicle FILE.yaml]  (the car's constants, also the diagnosis' nominal) [--rate HZ]
        [--stability-resamples N] [--min-inclusion F]  (the diagnosis' stability selection, as in diagnose)
        [--summarize DIR]  (only the table, from DIR/runs.jsonl of a sweep, finished or not)
        [--resume]  (keep the runs DIR/runs.jsonl already has, run the rest; same options as before)
        [--list-cases]  (print the grid's case labels, one a line, and exit)
        [--cases A,B]  (run only the grid's cases with these labels, e.g. steer_delay_large_s1)
        (full grid: 5 seeds, every effect at both sizes, 8 pairs, 20 effect-free; --reduced: 1 seed,
        3 pairs, 4 effect-free). Writes DIR/runs.jsonl, DIR/evidence_sweep.md, DIR/evidence_sweep.json.
Effects (key=value keys are the fields of evidence/truth_effects.hpp):
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

std::string usage() {
  std::string u = kEvidenceUsage;
  for (const auto& e : evidence::truth_effect_catalogue())
    u += "  " + e.name + ": " + e.form + " (small " + e.small + ", large " + e.large + ")" +
         (e.in_grid ? "" : " [not in the sweep's grid unless asked for: --effects " + e.name + "]") + "\n";
  return u;
}

int evidence_synth(int argc, char** argv) {
  evidence::EvidenceOptions o;
  std::string out;
  for (int i = 2; i < argc; ++i) {
    const std::string f = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(f + " needs a value");
      return argv[++i];
    };
    if (f == "--generator") value();
    else if (f == "--out") out = value();
    else if (f == "--effect") o.truth_names = evidence::set_truth_effects(value(), &o.truth);
    else if (f == "--seed") o.seed = static_cast<std::uint64_t>(number(f, value()));
    else if (f == "--duration") o.duration_s = number(f, value());
    else if (f == "--track") o.track = value();
    else if (f == "--direction") o.direction = value();
    else if (f == "--driver") o.driver = value();
    else if (f == "--speed-range") {
      const std::string v = value();
      const auto colon = v.find(':');
      if (colon == std::string::npos) throw UsageError(f + " expects MIN:MAX");
      o.speed_min_mps = number(f, v.substr(0, colon));
      o.speed_max_mps = number(f, v.substr(colon + 1));
    } else if (f == "--noise-scale") o.noise.scale = number(f, value());
    else if (f == "--glitch-rate") o.noise.glitch_rate = number(f, value());
    else if (f == "--drop-rate") o.noise.drop_rate = number(f, value());
    else if (f == "--vehicle") o.vehicle_yaml = value();
    else if (f == "--rate") o.log_dt_s = evidence::log_interval_s(number(f, value()), o.physics_dt_s);
    else if (f == "--help" || f == "-h") {
      std::fputs(usage().c_str(), stdout);
      return 0;
    } else throw UsageError("unknown option " + f);
  }
  if (out.empty()) throw UsageError("synth: --out FILE.csv is required");
  const auto r = evidence::generate_evidence(o, out);
  std::printf("wrote %s (%d rows; %s, %s, driver %s, crashes %d), %s, %s\n", r.csv.c_str(), r.rows, r.track.c_str(),
              r.direction.c_str(), r.driver.c_str(), r.crashes, r.clean_csv.c_str(), r.truth_json.c_str());
  std::printf("vehicle constants: %s (the nominal: mppi-fit diagnose --params %s)\n", r.vehicle_yaml.c_str(),
              r.vehicle_yaml.c_str());
  return 0;
}

int evidence_sweep(int argc, char** argv) {
  diagnose::EvidenceGrid grid;
  bool reduced = false, resume = false, list_cases = false;
  std::vector<std::string> only_cases;
  int seeds = -1, pairs = -1, clean = -1, jobs = 1;
  std::vector<std::string> sizes, effects;
  double duration = 60;
  diagnose::SelectionOptions selection;  // the diagnosis' defaults unless asked otherwise
  std::string out = "out/evidence_sweep", md_copy, summarize, vehicle;
  for (int i = 2; i < argc; ++i) {
    const std::string f = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(f + " needs a value");
      return argv[++i];
    };
    if (f == "--generator") value();
    else if (f == "--reduced") reduced = true;
    else if (f == "--resume") resume = true;
    else if (f == "--list-cases") list_cases = true;
    else if (f == "--cases") only_cases = split_list(value());
    else if (f == "--seeds") seeds = static_cast<int>(number(f, value()));
    else if (f == "--pairs") pairs = static_cast<int>(number(f, value()));
    else if (f == "--clean") clean = static_cast<int>(number(f, value()));
    else if (f == "--sizes") sizes = split_list(value());
    else if (f == "--effects") effects = split_list(value());
    else if (f == "--duration") duration = number(f, value());
    else if (f == "--jobs") jobs = std::max(1, static_cast<int>(number(f, value())));
    else if (f == "--out") out = value();
    else if (f == "--vehicle") vehicle = value();
    else if (f == "--stability-resamples") {
      const double n = number(f, value());
      if (n < 0 || n > 200 || n != static_cast<int>(n)) throw UsageError(f + " expects a whole number in [0, 200]");
      selection.stability_resamples = static_cast<int>(n);
    } else if (f == "--min-inclusion") {
      selection.min_inclusion_frequency = number(f, value());
      if (!(selection.min_inclusion_frequency >= 0 && selection.min_inclusion_frequency <= 1))
        throw UsageError(f + " expects a share in [0, 1]");
    } else if (f == "--rate") {
      grid.rate_hz = number(f, value());
      evidence::log_interval_s(grid.rate_hz);  // checked before the first run
    } else if (f == "--md") md_copy = value();
    else if (f == "--summarize") summarize = value();
    else if (f == "--help" || f == "-h") {
      std::fputs(usage().c_str(), stdout);
      return 0;
    } else throw UsageError("unknown option " + f);
  }
  if (!summarize.empty()) {  // the table from a (possibly unfinished) sweep's runs.jsonl
    const auto runs = diagnose::read_evidence_runs(summarize + "/runs.jsonl");
    const std::string md = diagnose::evidence_summary_markdown(runs);
    std::printf("%s", md.c_str());
    std::ofstream(summarize + "/evidence_sweep.md") << md;
    std::ofstream(summarize + "/evidence_sweep.json") << diagnose::evidence_summary_json(runs) << "\n";
    if (!md_copy.empty()) std::ofstream(md_copy) << md;
    return 0;
  }
  if (reduced) {
    const double rate_hz = grid.rate_hz;
    grid = diagnose::reduced_evidence_grid();
    grid.rate_hz = rate_hz;
  }
  if (seeds >= 0) grid.seeds = seeds;
  if (pairs >= 0) grid.pairs = pairs;
  if (clean >= 0) grid.clean = clean;
  if (!sizes.empty()) grid.sizes = sizes;
  grid.effects = effects;
  grid.duration_s = duration;
  grid.vehicle_yaml = vehicle;
  auto cases = diagnose::evidence_cases(grid);
  if (list_cases) {
    for (const auto& c : cases) std::printf("%s\n", c.label().c_str());
    return 0;
  }
  if (!only_cases.empty()) {
    std::vector<diagnose::EvidenceCase> kept;
    for (const auto& label : only_cases) {
      const auto it = std::find_if(cases.begin(), cases.end(), [&](const auto& c) { return c.label() == label; });
      if (it == cases.end()) throw UsageError("--cases: '" + label + "' is not a case of this grid (--list-cases)");
      kept.push_back(*it);
    }
    cases = std::move(kept);
  }
  std::filesystem::create_directories(out);
  std::vector<diagnose::EvidenceRun> runs(cases.size());
  std::vector<char> done(cases.size(), 0);
  const std::string jsonl_path = out + "/runs.jsonl";
  if (resume && std::filesystem::exists(jsonl_path)) {
    // A sweep cut short goes on where it stopped: runs already recorded (same case, no error) stay.
    std::size_t kept = 0;
    for (const auto& previous : diagnose::read_evidence_runs(jsonl_path))
      for (std::size_t k = 0; k < cases.size(); ++k)
        if (!done[k] && previous.error.empty() && previous.c.label() == cases[k].label() &&
            previous.c.assignments == cases[k].assignments) {
          runs[k] = previous;
          done[k] = 1;
          ++kept;
        }
    std::printf("resuming: %zu of %zu runs already in %s\n", kept, cases.size(), jsonl_path.c_str());
  }
  std::ofstream jsonl(jsonl_path, resume ? std::ios::app : std::ios::trunc);
  if (!jsonl) throw Error(jsonl_path + ": cannot write");
  std::atomic<std::size_t> next{0};
  std::mutex io;
  std::printf("%zu runs, %d job(s), stability selection: %d resamples, named at inclusion >= %.2f -> %s\n",
              cases.size(), jobs, selection.stability_resamples, selection.min_inclusion_frequency, out.c_str());
  auto worker = [&] {
    for (std::size_t k = next++; k < cases.size(); k = next++) {
      if (done[k]) continue;
      diagnose::DiagnoseOptions o;
      o.plots = false;
      o.selection = selection;
      runs[k] = diagnose::run_evidence_case(cases[k], out, grid.duration_s, o, grid.vehicle_yaml, grid.rate_hz);
      const auto& r = runs[k];
      std::lock_guard<std::mutex> lock(io);
      std::string named;
      for (const auto& s : r.named) named += (named.empty() ? "" : "+") + s;
      std::string once;
      for (const auto& s : r.crossed_once) once += (once.empty() ? "  crossed once: " : "+") + s;
      std::printf("[%zu/%zu] %-45s %-8s %-3s %-7s named %-30s right %d wrong %d  1-s RMSE %.3f -> %.3f (%.1f %%)%s%s%s\n",
                  k + 1, cases.size(), cases[k].label().c_str(), r.track.c_str(), r.direction.c_str(),
                  r.driver.c_str(), named.empty() ? "-" : named.c_str(), r.right, r.wrong, r.before_clean,
                  r.after_clean, 100 * r.reduction(), once.c_str(), r.error.empty() ? "" : "  ERROR: ",
                  r.error.c_str());
      std::fflush(stdout);
      jsonl << diagnose::evidence_run_json(r) << "\n" << std::flush;
    }
  };
  std::vector<std::thread> pool;
  for (int j = 0; j < jobs; ++j) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  const std::string md = diagnose::evidence_summary_markdown(runs);
  std::printf("\n%s", md.c_str());
  std::ofstream(out + "/evidence_sweep.md") << md;
  std::ofstream(out + "/evidence_sweep.json") << diagnose::evidence_summary_json(runs) << "\n";
  if (!md_copy.empty()) std::ofstream(md_copy) << md;
  return 0;
}

}  // namespace

// True when the arguments ask for the independent generator.
bool mppi_fit_wants_independent_generator(int argc, char** argv) {
  for (int i = 2; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--generator") return std::string(argv[i + 1]) == "independent";
  return false;
}

int mppi_fit_evidence(int argc, char** argv) {
  try {
    const std::string sub = argc > 1 ? argv[1] : "";
    for (int i = 2; i + 1 < argc; ++i)
      if (std::string(argv[i]) == "--generator" && std::string(argv[i + 1]) != "independent")
        throw UsageError("--generator: 'independent' (or leave it out for the built-in one)");
    if (sub == "synth") return evidence_synth(argc, argv);
    if (sub == "sweep") return evidence_sweep(argc, argv);
    throw UsageError("--generator independent goes with synth or sweep");
  } catch (const UsageError& e) {
    std::fprintf(stderr, "mppi-fit diagnose: %s\n%s", e.what(), usage().c_str());
    return 2;
  } catch (const mppi::Error& e) {
    std::fprintf(stderr, "mppi-fit diagnose: error: %s\n", e.what());
    return 1;
  }
}
