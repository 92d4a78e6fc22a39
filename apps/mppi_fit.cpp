// mppi-fit: parameter estimation and sim-vs-real tools; dispatches to a subcommand.
#include <cstdio>
#include <cstring>

#include "mppi_fit_commands.hpp"

namespace {

const char* kUsage = R"(usage: mppi-fit <command> [options]   (mppi-fit <command> --help for its options)
commands:
  estimate   estimate model parameters from a recording (UKF, joint UKF, ALM-UKF)
  convert    convert a shipped real-data recording into the project's recording format
  diagnose   compare a recording against the simulator's prediction (sim vs real)
  protocol   simulate the paper's estimation manoeuvres on the full-vehicle plant
  calibrate  fit a plant's drivetrain, brakes, steering and tyres to a learned dynamics model
)";

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const char* cmd = argv[1];
  if (std::strcmp(cmd, "estimate") == 0) return mppi_fit_estimate(argc - 1, argv + 1);
  if (std::strcmp(cmd, "convert") == 0) return mppi_fit_convert(argc - 1, argv + 1);
  if (std::strcmp(cmd, "diagnose") == 0) return mppi_fit_diagnose(argc - 1, argv + 1);
  if (std::strcmp(cmd, "protocol") == 0) return mppi_fit_protocol(argc - 1, argv + 1);
  if (std::strcmp(cmd, "calibrate") == 0) return mppi_fit_calibrate(argc - 1, argv + 1);
  std::fprintf(stderr, "mppi-fit: unknown command '%s'\n%s", cmd, kUsage);
  return 2;
}
