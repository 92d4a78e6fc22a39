// mppi-fit evaluate: score a written corrected model (corrected_model.yaml from mppi-fit diagnose)
// against its nominal model on any recording: the multi-step errors of both, as the diagnosis
// reports its held-out part (docs/DIAGNOSE.md, "Checking a correction on another run").
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "base/error.hpp"
#include "cli/app.hpp"
#include "cli/options.hpp"
#include "sysid/prepared_recording.hpp"
#include "diagnose/evaluate.hpp"
#include "diagnose/model_comparison.hpp"
#include "dynamics/corrected_model.hpp"
#include "mppi_fit_commands.hpp"

namespace {

using namespace mppi;
using namespace mppi::diagnose;

struct EvaluateArgs {
  std::string model_file, log, out;
  EvaluateOptions o;
};

int run_evaluate(EvaluateArgs& args) {
  try {
    const CorrectedModelFile model = load_corrected_model(args.model_file);
    EvaluateOptions o = args.o;
    if (o.rows == "heldout") {  // the rows the diagnosis held out, where the file says which
      const auto it = model.fitted_on.find("heldout");
      if (it == model.fitted_on.end())
        throw Error(args.model_file + ": --rows heldout needs the file's fitted_on.heldout (written by mppi-fit diagnose)");
      o.rows = it->second;
    }
    const PreparedRecording d = load_any(args.log);
    const EvaluateResult r = evaluate_corrected_model(model, args.model_file, d, o);
    std::printf("%s on %s (%zu rows scored, rows %s)\n", args.model_file.c_str(), d.source.c_str(), r.rows_scored,
                o.rows.c_str());
    std::printf("%10s %7s %23s %23s\n", "horizon", "starts", "normalised RMSE nominal", "corrected");
    for (std::size_t i = 0; i < r.nominal.size(); ++i)
      std::printf("%8.2f s %7d %23.4f %23.4f\n", r.nominal[i].horizon_s, r.nominal[i].starts,
                  r.nominal[i].normalized_rmse, r.corrected[i].normalized_rmse);
    std::printf("normalised RMSE at %.2g s: %.4f -> %.4f (%.1f %% reduction)\n", o.headline_horizon_s,
                r.headline_nominal, r.headline_corrected, 100 * r.reduction);
    if (!args.out.empty()) {
      const nlohmann::json j = {{"model_file", args.model_file},
                                {"log", d.source},
                                {"rows", o.rows},
                                {"rows_scored", r.rows_scored},
                                {"headline_horizon_s", o.headline_horizon_s},
                                {"headline", {{"nominal", r.headline_nominal}, {"corrected", r.headline_corrected},
                                              {"reduction", r.reduction}}},
                                {"nominal", horizon_metrics_json(r.nominal)},
                                {"corrected", horizon_metrics_json(r.corrected)}};
      const std::filesystem::path parent = std::filesystem::path(args.out).parent_path();
      if (!parent.empty()) std::filesystem::create_directories(parent);
      std::ofstream f(args.out);
      if (!f) throw Error("cannot write " + args.out);
      f << j.dump(2) << "\n";
      std::printf("wrote %s\n", args.out.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit evaluate: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

void add_evaluate_command(CLI::App& fit, FitCommands& commands) {
  auto args = std::make_shared<EvaluateArgs>();
  CLI::App* cmd = fit.add_subcommand(
      "evaluate", "score a corrected model (corrected_model.yaml of mppi-fit diagnose) against its nominal model on a "
                  "recording; a model and recording of different cars are refused, naming what differs");
  cmd->add_option("--model-file", args->model_file, "the corrected-model file")->type_name("FILE")->required();
  cmd->add_option("--log", args->log,
                  "the recording (project format, a shipped real recording as for diagnose, or a rosbag)")
      ->type_name("FILE")
      ->required();
  cmd->add_option("--rows", args->o.rows,
                  "rows scored: all | heldout (the rows the diagnosis held out, from the file's fitted_on) | a "
                  "fraction at the end (0.3) | a time range T0:T1 [s]")
      ->type_name("ROWS")
      ->default_str("all");
  cmd->add_option("--out", args->out, "write the figures as JSON")->type_name("FILE");
  cmd->add_option("--geometry-tolerance", args->o.geometry_tolerance,
                  "largest relative difference of mass and wheelbase between the model and the recording's "
                  "metadata")
      ->type_name("F")
      ->check(CLI::PositiveNumber);
  commands.add(cmd, [args] { return run_evaluate(*args); });
}
