// Built against an installed (and then copied) package: the simulator finds the network and
// the maps in that installation, not in the source tree, and drives a short closed loop.
// Usage: sim_consumer <installation prefix>; exits 0 only if all of that holds.
#include <cstdio>
#include <filesystem>
#include <string>

#include <sim/closed_loop.hpp>
#include <sim/data_dir.hpp>

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const std::string prefix = std::filesystem::canonical(argv[1]).string();
  const std::string data = std::filesystem::weakly_canonical(mppi::sim::data_dir()).string();
  std::printf("data_dir() = %s\n", data.c_str());
  if (data.rfind(prefix + "/", 0) != 0) {
    std::fprintf(stderr, "data_dir() is not inside the installation %s\n", prefix.c_str());
    return 1;
  }
  mppi::sim::ClosedLoopConfig config;  // the AutoRally network on the Gazebo oval
  config.controller.num_samples = 64;
  config.controller.horizon = 30;
  config.max_time_s = 2.0;
  config.progress = false;
  const mppi::sim::RunSummary s = mppi::sim::run_closed_loop(config);
  std::printf("drove %.1f s, max speed %.2f m/s\n", s.sim_time_s, s.max_speed_mps);
  return s.sim_time_s >= 1.9 && s.max_speed_mps > 0.5 ? 0 : 1;
}
