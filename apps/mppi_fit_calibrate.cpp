// mppi-fit calibrate: fits a physics plant's drivetrain, brake, steering and tyre parameters
// to a learned dynamics model (the AutoRally network) treated as the recording of the real car:
// the network is driven open loop through the paper's five manoeuvres (training and held-out
// command sequences from different seeds), and the plant's parameters are chosen to minimise
// its 1-s open-loop prediction error on the training set (sysid/plant_calibration.hpp). Reports
// the held-out normalised RMSE per channel and lead time before and after. docs/CALIBRATION.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "dynamics/autorally_nn.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/effects.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi/vehicle_state.hpp"
#include "mppi_fit_bag.hpp"
#include "mppi_fit_commands.hpp"
#include "sim/data_dir.hpp"
#include "sysid/estimable_models.hpp"
#include "sysid/manoeuvre_rollout.hpp"
#include "sysid/plant_calibration.hpp"
#include "sysid/vehicle_estimation.hpp"

namespace {

// The usage is kUsageHead, the --model line (calibrate_usage) and kUsageTail.
const char* kUsageHead = R"(usage: mppi-fit calibrate [options]
  --network FILE       learned dynamics used as the recording of the car
                       (default data/autorally/models/autorally_nnet_09_12_2018.npz)
)";

const char* kUsageTail = R"(  --params FILE        starting (and "before") parameters
                       (default data/config/autorally_<model>_uncalibrated.yaml)
  --estimate A,B,...   parameters to fit (default: max_steer_rad, stall_torque_Nm,
                       no_load_speed_mps, brake_torque_ratio, rolling_resistance,
                       aero_drag_kgpm (the full vehicle: drag_coefficient), tyre.B, tyre.C,
                       tyre.D, tyre.E, tyre.Sv); also
                       rear_tyre_B_scale, rear_tyre_C_scale, rear_tyre_D_scale (per-axle
                       tyres) and the single-track's actuator terms steer_lag_s,
                       throttle_lag_s, steer_cubic, steer_offset (then calibrated.yaml is a
                       corrected-model file: mppi-sim --plant corrected --plant-params)
  --train-s S          training command sequence length                     (100)
  --heldout-s S        held-out command sequence length                     (100)
  --seed N             training seed; the held-out sequence uses N + 1000   (1)
  --train-log FILE     also fit to this recording of the learned model (e.g. an mppi-sim
                       log.csv with --plant autorally-nn: closed-loop driving at the operating
                       point); repeatable. Logs with applied_steer / applied_throttle columns
                       are read with those as the commands (what the car received);
                       a run whose car was put back (a crash or stall) should be cut
                       there first: the log does not mark the jump
  --heldout-log FILE   also judge on this recording (a second table, fit_logs.md); repeatable
                       (a --train-log / --heldout-log may be a rosbag, FILE.bag: docs/ROSBAG.md)
  --topic-map FILE     rosbag logs: which topics hold the drive (YAML, docs/ROSBAG.md)
  --topic K=V[,K=V]    rosbag logs: over the topic map, e.g. pose=/odom
  --dither S,T         white noise (std) added to every steering / throttle
                       command of both sequences, as MPPI's applied commands
                       carry its exploration noise                          (0,0)
  --horizon S          open-loop prediction horizon of the objective        (1)
  --stride S           a rollout starts every S seconds                     (0.5)
  --iterations N       Levenberg-Marquardt iterations at most               (40)
  --out DIR            calibrated.yaml, fit.md (errors per channel and lead, steering
                       step response), summary.txt, train.csv, heldout.csv
                                                                            (out/calibrate)
)";

// The option help with the --model choices from the estimable models.
std::string calibrate_usage() {
  const std::size_t default_column = 74;
  std::string model_line = "  --model NAME         ";
  const std::vector<std::string> names = mppi::sysid::estimable_model_names();
  for (std::size_t i = 0; i < names.size(); ++i) model_line += (i == 0 ? "" : " | ") + names[i];
  model_line.resize(std::max(default_column, model_line.size() + 1), ' ');
  model_line += "(" + std::string(mppi::models::SingleTrackModel::kName) + ")\n";
  return kUsageHead + model_line + kUsageTail;
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

double number(const std::string& flag, const std::string& s) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != s.size() || s.empty()) throw mppi::Error(flag + " expects a number, got '" + s + "'");
  return v;
}

void write_recording(const mppi::sim::Recording& rec, const std::string& path) {
  const std::vector<std::string> extras(rec.columns.begin() + mppi::sim::kRecordingRequiredColumns.size(),
                                        rec.columns.end());
  std::vector<std::pair<std::string, std::string>> meta(rec.metadata.begin(), rec.metadata.end());
  mppi::sim::RecordingWriter w(path, extras, meta);
  std::vector<double> row(rec.columns.size());
  for (std::size_t i = 0; i < rec.rows(); ++i) {
    for (std::size_t c = 0; c < row.size(); ++c) row[c] = rec.data[c][i];
    w.write_row(row);
  }
  w.close();
}

// Markdown table: channel x lead, before / after / change.
std::string error_table(const mppi::sysid::PredictionError& before, const mppi::sysid::PredictionError& after) {
  std::string s = "| channel | lead [s] | NRMSE before | NRMSE after | change |\n|---|---|---|---|---|\n";
  char line[200];
  for (std::size_t c = 0; c < before.channels.size(); ++c) {
    for (std::size_t h = 0; h < before.horizons_s.size(); ++h) {
      const double b = before.nrmse_at[c][h], a = after.nrmse_at[c][h];
      std::snprintf(line, sizeof line, "| %s | %.2f | %.3f | %.3f | %+.0f %% |\n", before.channels[c].c_str(),
                    before.horizons_s[h], b, a, 100 * (a - b) / b);
      s += line;
    }
    std::snprintf(line, sizeof line, "| %s | 0-1 (all leads) | %.3f | %.3f | %+.0f %% |\n",
                  before.channels[c].c_str(), before.nrmse[c], after.nrmse[c],
                  100 * (after.nrmse[c] - before.nrmse[c]) / before.nrmse[c]);
    s += line;
  }
  std::snprintf(line, sizeof line, "| **mean** | 0-1 (all leads) | **%.3f** | **%.3f** | **%+.0f %%** |\n",
                before.mean_nrmse, after.mean_nrmse, 100 * (after.mean_nrmse - before.mean_nrmse) / before.mean_nrmse);
  s += line;
  return s;
}

// Yaw rate after a steering step (0 -> 0.3 at 6 m/s, throttle 0.3) of the learned model and of
// the plant before and after the fit: the learned model holds no actuator state, so how it
// answers a step shows what a plant needs to follow it (docs/CALIBRATION.md).
std::string step_response_table(const mppi::sysid::RolloutStep& net_step, const mppi::sysid::VehicleModelSpec& spec,
                                const std::vector<double>& fitted) {
  const double speed = 6.0, steer = 0.3, throttle = 0.3, dt = 0.02;
  const std::vector<double> leads = {0.02, 0.04, 0.1, 0.2, 0.3, 0.5, 1.0};
  std::vector<double> x(mppi::AutoRallyNetwork::kNx, 0.0);
  x[mppi::state::kVx] = speed;
  const double u[2] = {steer, throttle};
  const std::vector<double> net = mppi::sysid::step_response(net_step, x, u, mppi::state::kYawRate, leads, dt);
  const std::vector<double> before = mppi::sysid::steering_step_yaw_rate(spec, spec.nominal, speed, steer, throttle, leads, dt);
  const std::vector<double> after = mppi::sysid::steering_step_yaw_rate(spec, fitted, speed, steer, throttle, leads, dt);
  std::string s = "steering step 0 -> 0.3 at 6 m/s (throttle 0.3), yaw rate [rad/s]:\n\n"
                  "| after [s] | learned model | plant before | plant after |\n|---|---|---|---|\n";
  char line[160];
  for (std::size_t i = 0; i < leads.size(); ++i) {
    std::snprintf(line, sizeof line, "| %.2f | %.3f | %.3f | %.3f |\n", leads[i], net[i], before[i], after[i]);
    s += line;
  }
  return s;
}

// The model's shipped data file with "_uncalibrated" before ".yaml": the values before calibration.
std::string uncalibrated_file(std::string default_file) {
  default_file.insert(default_file.rfind(".yaml"), "_uncalibrated");
  return mppi::sim::data_file(default_file);
}

}  // namespace

int mppi_fit_calibrate(int argc, char** argv) {
  using namespace mppi;
  using namespace mppi::sysid;
  std::string network_file, model = models::SingleTrackModel::kName, params_file, out_dir = "out/calibrate";
  std::vector<std::string> names = {"max_steer_rad", "stall_torque_Nm", "no_load_speed_mps", "brake_torque_ratio",
                                    "rolling_resistance", "aero_drag_kgpm", "tyre.B", "tyre.C", "tyre.D",
                                    "tyre.E", "tyre.Sv"};
  std::vector<std::string> train_logs, heldout_logs;
  ManoeuvreOptions train_opt, held_opt;
  train_opt.duration_s = held_opt.duration_s = 100;
  CalibrationOptions cal;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw Error(a + " expects a value");
        return argv[++i];
      };
      if (a == "--help" || a == "-h") {
        std::fputs(calibrate_usage().c_str(), stdout);
        return 0;
      } else if (a == "--network") {
        network_file = value();
      } else if (a == "--model") {
        model = value();
        with_estimable_model(model, []<class E>() {}, "--model");
      } else if (a == "--params") {
        params_file = value();
      } else if (a == "--estimate") {
        names = split_list(value());
      } else if (a == "--train-s") {
        train_opt.duration_s = number(a, value());
      } else if (a == "--heldout-s") {
        held_opt.duration_s = number(a, value());
      } else if (a == "--seed") {
        const double s = number(a, value());
        if (!(s >= 0 && s == std::floor(s))) throw Error("--seed expects a non-negative integer");
        train_opt.seed = static_cast<std::uint64_t>(s);
      } else if (a == "--train-log") {
        train_logs.push_back(value());
      } else if (a == "--topic-map") {
        fit_bag_options().topic_map_file = value();
      } else if (a == "--topic") {
        fit_bag_options().topics.push_back(value());
      } else if (a == "--heldout-log") {
        heldout_logs.push_back(value());
      } else if (a == "--dither") {
        const std::vector<std::string> parts = split_list(value());
        if (parts.size() != 2) throw Error("--dither expects STEER_STD,THROTTLE_STD");
        train_opt.steer_dither_std = held_opt.steer_dither_std = number(a, parts[0]);
        train_opt.throttle_dither_std = held_opt.throttle_dither_std = number(a, parts[1]);
      } else if (a == "--horizon") {
        cal.error.horizon_s = number(a, value());
        cal.error.report_horizons_s = {0.1 * cal.error.horizon_s, 0.25 * cal.error.horizon_s,
                                       0.5 * cal.error.horizon_s, cal.error.horizon_s};
      } else if (a == "--stride") {
        cal.error.stride_s = number(a, value());
      } else if (a == "--iterations") {
        cal.max_iterations = static_cast<int>(number(a, value()));
      } else if (a == "--out") {
        out_dir = value();
      } else {
        throw Error("unknown option '" + a + "'");
      }
    }
    held_opt.seed = train_opt.seed + 1000;
    std::string why;
    if (!train_opt.is_valid(&why) || !held_opt.is_valid(&why) || !cal.is_valid(&why)) throw Error(why);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit calibrate: %s\n%s", e.what(), calibrate_usage().c_str());
    return 2;
  }

  try {
    const std::string net_path =
        network_file.empty() ? sim::data_file("autorally/models/autorally_nnet_09_12_2018.npz") : network_file;
    const AutoRallyNetwork net = AutoRallyNetwork::load(net_path);
    const RolloutStep net_step = [&net](std::vector<double>& x, const double u[2], double dt) {
      double dx[AutoRallyNetwork::kNx];
      net.derivatives(x.data(), u, dx);
      for (int i = 0; i < AutoRallyNetwork::kNx; ++i) x[static_cast<std::size_t>(i)] += dx[i] * dt;
    };
    const std::vector<double> x0(AutoRallyNetwork::kNx, 0.0);
    std::vector<sim::Recording> train_pieces = {roll_out_manoeuvres(net_step, x0, train_opt)};
    for (const std::string& f : train_logs) train_pieces.push_back(read_learned_model_log(f));
    const sim::Recording train_table = join_recordings(train_pieces);
    const sim::Recording held_table = roll_out_manoeuvres(net_step, x0, held_opt);
    const PreparedRecording train = prepare(train_table, "the training recording", 3);
    const PreparedRecording held = prepare(held_table, "the held-out manoeuvres", 3);
    std::vector<sim::Recording> held_log_pieces;
    for (const std::string& f : heldout_logs) held_log_pieces.push_back(read_learned_model_log(f));

    VehicleModelSpec spec;
    bool actuator_terms = false;
    with_estimable_model(model, [&]<class E>() {
      if (params_file.empty()) params_file = uncalibrated_file(E::Descriptor::kDefaultFile);
      for (std::string& n : names)
        if (n == "aero_drag_kgpm") n = E::kDragParam;
      spec = E::spec(E::load_params(params_file), names);
      actuator_terms = E::kActuatorTerms;
    });

    const std::vector<double> train_scales = channel_scales(train, cal.error.channels);
    const std::vector<double> held_scales = channel_scales(held, cal.error.channels);
    std::printf("calibrating %s (%zu parameters) to %s: %.0f s training (%zu logs besides), %.0f s held out\n",
                model.c_str(), names.size(), net_path.c_str(), train_opt.duration_s, train_logs.size(),
                held_opt.duration_s);
    const CalibrationResult fit = calibrate(spec, train, train_scales, cal);
    const PredictionError before = prediction_error(spec, spec.nominal, held, held_scales, cal.error);
    const PredictionError after = prediction_error(spec, fit.values, held, held_scales, cal.error);
    const PredictionError train_after = prediction_error(spec, fit.values, train, train_scales, cal.error);

    std::filesystem::create_directories(out_dir);
    write_recording(train_table, out_dir + "/train.csv");
    write_recording(held_table, out_dir + "/heldout.csv");
    {
      // Fitted actuator terms (steer_lag_s, ...) are effects of the corrected model: then the
      // file is a corrected-model file (the plant as nominal_params, the actuators as effects)
      // that mppi-sim loads with --plant corrected --plant-params FILE.
      // Only actuator effects: aero_drag_kgpm is also the plant's own key (and an extra-force effect).
      CorrectedModelFile corrected;
      bool actuators = false;
      for (std::size_t i = 0; i < fit.names.size(); ++i)
        for (const EffectSpec& e : effect_table())
          for (const EffectParamSpec& q : e.params)
            if (e.hook == EffectHook::kActuator && fit.names[i] == q.name) {
              corrected.effects.*(q.member) = fit.values[i];
              actuators = true;
            }
      std::ofstream y(out_dir + "/calibrated.yaml");
      const std::string comment = model + " parameters calibrated by mppi-fit calibrate to " + net_path;
      // Only the single-track's spec has actuator terms (E::kActuatorTerms): the file's nominal.
      if (actuators && actuator_terms) {
        corrected.nominal = single_track_params_from_yaml(spec.to_yaml(fit.values), out_dir + "/calibrated.yaml");
        for (const EffectSpec& e : effect_table())
          for (const EffectParamSpec& q : e.params)
            if (corrected.effects.*(q.member) != EffectParams{}.*(q.member)) corrected.selected.push_back(e.id);
        y << corrected_model_to_yaml(corrected, comment);
      } else {
        y << "# " << comment << "\n" << spec.to_yaml(fit.values);
      }
    }
    std::string summary;
    char line[256];
    std::snprintf(line, sizeof line, "parameter | start | calibrated | at box edge\n");
    summary += line;
    for (std::size_t i = 0; i < fit.names.size(); ++i) {
      std::snprintf(line, sizeof line, "%s | %.5g | %.5g | %s\n", fit.names[i].c_str(), fit.initial[i],
                    fit.values[i], fit.at_bound[i] ? "yes" : "no");
      summary += line;
    }
    std::snprintf(line, sizeof line,
                  "training cost (mean squared normalised residual): %.4f -> %.4f in %d iterations, %d evaluations\n"
                  "training mean NRMSE after: %.3f\nheld-out 1-s mean NRMSE: %.3f -> %.3f (%+.0f %%), %d rollouts\n",
                  fit.cost_history.front(), fit.cost_history.back(), fit.iterations, fit.evaluations,
                  train_after.mean_nrmse, before.mean_nrmse, after.mean_nrmse,
                  100 * (after.mean_nrmse - before.mean_nrmse) / before.mean_nrmse, after.rollouts);
    summary += line;
    std::string table = error_table(before, after);
    if (!held_log_pieces.empty()) {
      const PreparedRecording held_logs = prepare(join_recordings(held_log_pieces), "the held-out logs", 3);
      const std::vector<double> log_scales = channel_scales(held_logs, cal.error.channels);
      const PredictionError log_before = prediction_error(spec, spec.nominal, held_logs, log_scales, cal.error);
      const PredictionError log_after = prediction_error(spec, fit.values, held_logs, log_scales, cal.error);
      const std::string log_table = error_table(log_before, log_after);
      std::snprintf(line, sizeof line, "held-out logs 1-s mean NRMSE: %.3f -> %.3f (%+.0f %%), %d rollouts\n",
                    log_before.mean_nrmse, log_after.mean_nrmse,
                    100 * (log_after.mean_nrmse - log_before.mean_nrmse) / log_before.mean_nrmse,
                    log_after.rollouts);
      summary += line;
      std::ofstream(out_dir + "/fit_logs.md") << log_table;
      table += "\nheld-out logs:\n" + log_table;
    }
    table += "\n" + step_response_table(net_step, spec, fit.values);
    std::ofstream(out_dir + "/summary.txt") << summary;
    std::ofstream(out_dir + "/fit.md") << table;
    std::fputs(summary.c_str(), stdout);
    std::fputs(table.c_str(), stdout);
    std::printf("wrote %s/{calibrated.yaml,fit.md,summary.txt,train.csv,heldout.csv}\n", out_dir.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit calibrate: %s\n", e.what());
    return 1;
  }
}

// `mppi-fit calibrate` keeps its own option parser (mppi_fit_calibrate above): the subcommand
// passes everything after it through.
void add_calibrate_command(CLI::App& fit, FitCommands& commands) {
  CLI::App* cmd = fit.add_subcommand(
      "calibrate", "fit a plant's drivetrain, brakes, steering and tyres to a learned dynamics model "
                   "(calibrate --help lists its options)");
  cmd->prefix_command();
  cmd->set_help_flag();
  commands.add(cmd, [cmd] {
    std::vector<std::string> args = cmd->remaining();
    std::string name = "calibrate";
    std::vector<char*> argv = {name.data()};
    for (auto& a : args) argv.push_back(a.data());
    return mppi_fit_calibrate(static_cast<int>(argv.size()), argv.data());
  });
}
