// mppi-fit protocol: the paper's estimation protocol in simulation (sysid/protocol.hpp).
#include <cstdint>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>

#include "cli/app.hpp"
#include "cli/options.hpp"
#include "dynamics/models/full_vehicle_model.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi_fit_commands.hpp"
#include "sim/data_dir.hpp"
#include "sysid/protocol.hpp"
#include "sysid/protocol_plot.hpp"

namespace {

struct ProtocolArgs {
  std::string params_path, out = "out/protocol", layout = "interleaved";
  mppi::sysid::ProtocolOptions options;
  double noise_scale = 1.0;
};

int run_protocol(ProtocolArgs& args) {
  mppi::sysid::ProtocolOptions options = args.options;
  try {
    options.layout = mppi::sysid::parse_protocol_layout(args.layout);
  } catch (const std::exception& e) {
    throw mppi::cli::usage_error("--layout", e.what());
  }
  for (double* s : {&options.position_noise_m, &options.yaw_noise_rad, &options.velocity_noise_mps,
                    &options.rate_noise_radps, &options.angle_noise_rad, &options.accel_noise_mps2,
                    &options.wheel_noise_radps})
    *s *= args.noise_scale;
  try {
    const mppi::FullVehicleParams params = mppi::load_full_vehicle_params(
        args.params_path.empty() ? mppi::sim::data_file("config/autorally_full_vehicle_uncalibrated.yaml") : args.params_path);
    const auto run = mppi::sysid::run_protocol(params, options);
    mppi::sysid::write_protocol(run, params, args.out);
    mppi::sysid::plot_protocol(run, args.out + "/protocol.png");
    std::printf("protocol: %zu training rows, %zu validation rows -> %s/{train,validation,truth}.csv, truth.yaml, protocol.png\n",
                run.training.rows(), run.validation.rows(), args.out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit protocol: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

void add_protocol_command(CLI::App& fit, FitCommands& commands) {
  auto args = std::make_shared<ProtocolArgs>();
  mppi::sysid::ProtocolOptions& o = args->options;
  CLI::App* cmd = fit.add_subcommand("protocol", "simulate the paper's estimation manoeuvres on the full-vehicle plant");
  cmd->footer(
      "Drives the simulated full-vehicle plant (known parameters) through the paper's five manoeuvres\n"
      "(low speed, zig-zag, straight acceleration and braking, sliding, high speed; 20 s of each) and a\n"
      "held-out 13 s lap-like segment, with sensor noise. By default the manoeuvres are interleaved as a\n"
      "human driver mixes them (a 20 s cycle of five 4 s pieces, repeated); --layout sequential drives\n"
      "each for its whole 20 s in turn. Writes DIR/train.csv, DIR/validation.csv\n"
      "(measured, docs/RECORDING_FORMAT.md), DIR/truth.csv (noise-free states), DIR/truth.yaml,\n"
      "DIR/protocol.png.\n\n" +
      mppi::cli::model_parameter_help(mppi::models::FullVehicleModel::kName));
  cmd->add_option("--params", args->params_path,
                  "full-vehicle parameters of the plant (YAML, keys below; default "
                  "data/config/autorally_full_vehicle_uncalibrated.yaml: the paper's values)")
      ->type_name("FILE");
  mppi::cli::add_out_option(*cmd, args->out, "output folder");
  mppi::cli::add_seed_option(*cmd, o.seed, "sensor-noise seed");
  cmd->add_option("--manoeuvre-s", o.manoeuvre_duration_s, "total time in each manoeuvre")->type_name("S");
  using mppi::sysid::ProtocolLayout;
  cmd->add_option("--layout", args->layout, "interleaved | sequential")
      ->type_name("L")
      ->check(CLI::IsMember({mppi::sysid::protocol_layout_name(ProtocolLayout::interleaved),
                             mppi::sysid::protocol_layout_name(ProtocolLayout::sequential)})
                  .description(""));
  cmd->add_option("--piece-s", o.piece_duration_s, "interleaved: duration of one manoeuvre piece (cycle = 5 pieces)")
      ->type_name("S");
  cmd->add_option("--validation-s", o.validation_duration_s, "duration of the held-out segment")->type_name("S");
  cmd->add_option("--noise-scale", args->noise_scale,
                  "multiply every sensor-noise standard deviation by F (0 = no noise)")
      ->type_name("F");
  commands.add(cmd, [args] { return run_protocol(*args); });
}
