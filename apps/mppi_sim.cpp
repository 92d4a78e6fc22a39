// mppi-sim: MPPI driving laps of a built-in track in the headless simulator.
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "mppi/error.hpp"
#include "dynamics/model_registry.hpp"
#include "sim/closed_loop.hpp"
#include "sim/summary.hpp"

namespace {

const char* kUsage = R"(usage: mppi-sim [options]
  --track NAME         gazebo | marietta | ccrf                      (default gazebo)
  --clockwise          drive clockwise (default counter-clockwise)
  --model NAME         controller model: a model below, or corrected (a nominal model +
                       effects from mppi-fit diagnose, in --model-params)   (autorally-nn)
  --plant NAME         simulated car: a model below, or corrected            (single-track)
  --list-models        every model with its data file, states and parameters
  --speed MPS          target speed [m/s]                            (6)
  --laps N             laps to drive                                 (5)
  --max-time S         stop after S simulated seconds (default: from the laps)
  --samples K          MPPI samples per step                         (1920)
  --horizon T          MPPI time steps                               (100)
  --iterations N       MPPI iterations per step                      (1)
  --lambda L           MPPI temperature                              (6)
  --smoothing W        Savitzky-Golay window over the plan, 0 = off  (0)
  --seed N             noise seed                                    (1)
  --threads N          CPU threads, 0 = all                          (0)
  --backend NAME       auto | cpu | vulkan: auto takes a GPU through Vulkan if
                       there is one, else the CPU; vulkan also takes a CPU Vulkan
                       device (lavapipe); MPPI_VULKAN_DEVICE=<index|name> picks one (auto)
  --inject-device-loss-at-step N
                       fault drill: the backend fails like a lost GPU after N control steps;
                       the run goes on on the CPU backend (summary.json: backend_switches)
  --cost-config FILE   AutoRally cost weights (YAML)
  --plant-params FILE  the plant's data file (YAML parameters, or a corrected-model file)
  --model-params FILE  the controller model's data file (the same kinds)
  --network FILE       weights (.npz) of a learned model, when no --*-params file is given
  --out DIR            write DIR/log.csv, DIR/track.png, DIR/summary.json (default out/sim)
  --json               print summary.json to stdout
  --quiet              no progress lines
)";

[[noreturn]] void usage_error(const std::string& msg) {
  std::fprintf(stderr, "mppi-sim: %s\n%s", msg.c_str(), kUsage);
  std::exit(2);
}

double parse_number(const std::string& flag, const std::string& text) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size()) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    usage_error(flag + " expects a number, got '" + text + "'");
  }
}

int parse_int(const std::string& flag, const std::string& text) {
  const double v = parse_number(flag, text);
  if (v != static_cast<int>(v)) usage_error(flag + " expects an integer, got '" + text + "'");
  return static_cast<int>(v);
}

}  // namespace

int main(int argc, char** argv) {
  mppi::sim::ClosedLoopConfig config;
  config.out_dir = "out/sim";
  config.backend = mppi::BackendChoice::kAuto;
  bool print_json = false;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage_error(flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--help" || flag == "-h") {
      std::fputs(kUsage, stdout);
      std::printf("\nmodels: %s\n", mppi::model_names().c_str());
      return 0;
    } else if (flag == "--list-models") {
      std::fputs(mppi::models_help().c_str(), stdout);
      return 0;
    } else if (flag == "--track") config.track = value();
    else if (flag == "--clockwise") config.clockwise = true;
    else if (flag == "--model") config.model = value();
    else if (flag == "--plant") config.plant = value();
    else if (flag == "--speed") config.target_speed_mps = parse_number(flag, value());
    else if (flag == "--laps") config.laps = parse_int(flag, value());
    else if (flag == "--max-time") config.max_time_s = parse_number(flag, value());
    else if (flag == "--samples") config.controller.num_samples = parse_int(flag, value());
    else if (flag == "--horizon") config.controller.horizon = parse_int(flag, value());
    else if (flag == "--iterations") config.controller.iterations = parse_int(flag, value());
    else if (flag == "--lambda") config.controller.lambda = static_cast<float>(parse_number(flag, value()));
    else if (flag == "--smoothing") config.controller.smoothing_window = parse_int(flag, value());
    else if (flag == "--seed") config.controller.seed = static_cast<std::uint64_t>(parse_int(flag, value()));
    else if (flag == "--threads") config.controller.num_threads = parse_int(flag, value());
    else if (flag == "--backend") {
      try {
        config.backend = mppi::parse_backend_choice(value());
      } catch (const mppi::Error& e) {
        usage_error(e.what());
      }
    }
    else if (flag == "--inject-device-loss-at-step") config.inject_device_loss_at_step = parse_int(flag, value());
    else if (flag == "--cost-config") config.cost_params_yaml = value();
    else if (flag == "--plant-params") config.plant_params_yaml = value();
    else if (flag == "--model-params") config.model_params_yaml = value();
    else if (flag == "--network") config.network_npz = value();
    else if (flag == "--out") config.out_dir = value();
    else if (flag == "--json") print_json = true;
    else if (flag == "--quiet") config.progress = false;
    else usage_error("unknown option " + flag);
  }
  try {
    if (config.progress)
      std::fprintf(stderr, "mppi-sim: %s track, model %s, plant %s, %.1f m/s, K = %d, T = %d, seed %llu\n",
                   config.track.c_str(), config.model.c_str(), config.plant.c_str(),
                   config.target_speed_mps, config.controller.num_samples, config.controller.horizon,
                   static_cast<unsigned long long>(config.controller.seed));
    const mppi::sim::RunSummary summary = mppi::sim::run_closed_loop(config);
    if (config.progress)
      std::fprintf(stderr, "done: %d/%d laps, %d crashes, mean %.2f m/s, max %.2f m/s, optimizer p50 %.2f ms p99 %.2f ms -> %s\n",
                   summary.laps_completed, config.laps, summary.crashes, summary.mean_speed_mps,
                   summary.max_speed_mps, summary.optimizer_ms_p50, summary.optimizer_ms_p99,
                   config.out_dir.c_str());
    if (print_json) std::cout << mppi::sim::to_json(summary) << std::endl;
    return summary.finished ? 0 : 1;
  } catch (const mppi::Error& e) {
    std::fprintf(stderr, "mppi-sim: error: %s\n", e.what());
    return 2;
  }
}
