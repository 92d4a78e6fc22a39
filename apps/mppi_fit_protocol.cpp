// mppi-fit protocol: the paper's estimation protocol in simulation (sysid/protocol.hpp).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>

#include "dynamics/vehicle_params.hpp"
#include "mppi_fit_commands.hpp"
#include "sim/data_dir.hpp"
#include "sysid/protocol.hpp"
#include "sysid/protocol_plot.hpp"

namespace {

const char* kProtocolUsage = R"(usage: mppi-fit protocol [options]
Drives the simulated full-vehicle plant (known parameters) through the paper's five manoeuvres
(low speed, zig-zag, straight acceleration and braking, sliding, high speed; 20 s of each) and a
held-out 13 s lap-like segment, with sensor noise. By default the manoeuvres are interleaved as a
human driver mixes them (a 20 s cycle of five 4 s pieces, repeated); --layout sequential drives
each for its whole 20 s in turn. Writes DIR/train.csv, DIR/validation.csv
(measured, docs/RECORDING_FORMAT.md), DIR/truth.csv (noise-free states), DIR/truth.yaml,
DIR/protocol.png.
  --params FILE       full-vehicle parameters of the plant (default data/config/autorally_full_vehicle.yaml)
  --out DIR           output folder (default out/protocol)
  --seed N            sensor-noise seed (1)
  --manoeuvre-s S     total time in each manoeuvre (20)
  --layout L          interleaved | sequential (interleaved)
  --piece-s S         interleaved: duration of one manoeuvre piece (4; cycle = 5 pieces)
  --validation-s S    duration of the held-out segment (13)
  --noise-scale F     multiply every sensor-noise standard deviation by F (1; 0 = no noise)
)";

}  // namespace

int mppi_fit_protocol(int argc, char** argv) {
  std::string params_path, out = "out/protocol";
  mppi::sysid::ProtocolOptions options;
  double noise_scale = 1.0;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      std::fputs(kProtocolUsage, stdout);
      return 0;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "mppi-fit protocol: %s needs a value\n%s", flag.c_str(), kProtocolUsage);
      return 2;
    }
    const char* value = argv[++i];
    char* end = nullptr;
    auto number = [&]() {
      const double v = std::strtod(value, &end);
      if (end == value || *end != '\0') throw std::invalid_argument(flag + ": not a number: " + value);
      return v;
    };
    try {
      if (flag == "--params") params_path = value;
      else if (flag == "--out") out = value;
      else if (flag == "--seed") options.seed = static_cast<std::uint64_t>(number());
      else if (flag == "--manoeuvre-s") options.manoeuvre_duration_s = number();
      else if (flag == "--layout") options.layout = mppi::sysid::parse_protocol_layout(value);
      else if (flag == "--piece-s") options.piece_duration_s = number();
      else if (flag == "--validation-s") options.validation_duration_s = number();
      else if (flag == "--noise-scale") noise_scale = number();
      else {
        std::fprintf(stderr, "mppi-fit protocol: unknown option %s\n%s", flag.c_str(), kProtocolUsage);
        return 2;
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mppi-fit protocol: %s\n", e.what());
      return 2;
    }
  }
  for (double* s : {&options.position_noise_m, &options.yaw_noise_rad, &options.velocity_noise_mps,
                    &options.rate_noise_radps, &options.angle_noise_rad, &options.accel_noise_mps2,
                    &options.wheel_noise_radps})
    *s *= noise_scale;
  try {
    const mppi::FullVehicleParams params = mppi::load_full_vehicle_params(
        params_path.empty() ? mppi::sim::data_file("config/autorally_full_vehicle.yaml") : params_path);
    const auto run = mppi::sysid::run_protocol(params, options);
    mppi::sysid::write_protocol(run, params, out);
    mppi::sysid::plot_protocol(run, out + "/protocol.png");
    std::printf("protocol: %zu training rows, %zu validation rows -> %s/{train,validation,truth}.csv, truth.yaml, protocol.png\n",
                run.training.rows(), run.validation.rows(), out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit protocol: %s\n", e.what());
    return 1;
  }
  return 0;
}
