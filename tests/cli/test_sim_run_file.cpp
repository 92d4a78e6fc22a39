// mppi-sim's command line and its YAML run file (cli/sim_command_line.hpp, cli/run_file.hpp):
// the file and the equivalent flags give the same configuration, the command line wins over the
// file, bad keys and values are refused by name, and --dump-config round-trips.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli/app.hpp"
#include "cli/sim_command_line.hpp"
#include "test_data.hpp"

namespace {

using mppi::cli::SimCommandLine;

// A YAML file under the temporary folder, removed with the object.
struct TempFile {
  std::filesystem::path path;
  explicit TempFile(const std::string& text) {
    static std::atomic<int> counter{0};
    path = std::filesystem::temp_directory_path() /
           ("mppi_cli_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".yaml");
    std::ofstream(path) << text;
  }
  ~TempFile() { std::filesystem::remove(path); }
  std::string str() const { return path.string(); }
};

// Parses as mppi-sim does; `dump` receives --dump-config's text.
SimCommandLine parse_sim(const std::vector<std::string>& args, std::string* dump = nullptr) {
  CLI::App app{"", "mppi-sim"};
  SimCommandLine cl;
  mppi::cli::add_sim_options(app, cl);
  mppi::cli::parse_args(app, args, [&] { mppi::cli::finish_sim_options(app, cl); });
  if (dump) *dump = mppi::cli::dump_run_file(app);
  return cl;
}

// The message of the CLI11 error that parsing `args` throws ("" if none).
std::string parse_error(const std::vector<std::string>& args) {
  try {
    parse_sim(args);
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return "";
}

// Field by field: everything a run reads.
void require_same(const SimCommandLine& a, const SimCommandLine& b) {
  const mppi::sim::ClosedLoopConfig &x = a.config, &y = b.config;
  CHECK(x.track == y.track);
  CHECK(x.clockwise == y.clockwise);
  CHECK(x.model == y.model);
  CHECK(x.plant == y.plant);
  CHECK(x.target_speed_mps == y.target_speed_mps);
  CHECK(x.target_speed_schedule == y.target_speed_schedule);
  CHECK(x.laps == y.laps);
  CHECK(x.max_time_s == y.max_time_s);
  const mppi::ControllerOptions &p = x.controller, &q = y.controller;
  CHECK(p.num_samples == q.num_samples);
  CHECK(p.horizon == q.horizon);
  CHECK(p.dt_s == q.dt_s);
  CHECK(p.iterations == q.iterations);
  CHECK(p.lambda == q.lambda);
  CHECK(p.gamma == q.gamma);
  CHECK(p.noise_std == q.noise_std);
  CHECK(p.control_min == q.control_min);
  CHECK(p.control_max == q.control_max);
  CHECK(p.safe_control == q.safe_control);
  CHECK(p.smoothing_window == q.smoothing_window);
  CHECK(p.smoothing_order == q.smoothing_order);
  CHECK(p.seed == q.seed);
  CHECK(p.num_threads == q.num_threads);
  CHECK(p.schedule == q.schedule);
  CHECK(x.backend == y.backend);
  CHECK(x.cost_params_yaml == y.cost_params_yaml);
  CHECK(x.cost_map_npz == y.cost_map_npz);
  CHECK(x.plant_params_yaml == y.plant_params_yaml);
  CHECK(x.model_params_yaml == y.model_params_yaml);
  CHECK(x.network_npz == y.network_npz);
  CHECK(x.actuators.steer_rate_per_s == y.actuators.steer_rate_per_s);
  CHECK(x.actuators.throttle_rate_per_s == y.actuators.throttle_rate_per_s);
  CHECK(x.actuators.steer_min == y.actuators.steer_min);
  CHECK(x.actuators.steer_max == y.actuators.steer_max);
  CHECK(x.actuators.throttle_min == y.actuators.throttle_min);
  CHECK(x.actuators.throttle_max == y.actuators.throttle_max);
  CHECK(x.plant_dt_s == y.plant_dt_s);
  CHECK(x.out_dir == y.out_dir);
  CHECK(x.progress == y.progress);
  CHECK(x.through_chassis == y.through_chassis);
  CHECK(a.print_json == b.print_json);
  CHECK(a.quiet == b.quiet);
  CHECK(a.data_dir == b.data_dir);
}

// Every option set away from its default, as flags and as the same run file.
const std::string kDataDir = MPPI_TEST_DATA_DIR;
const std::vector<std::string> kFlags = {
    "--track", "marietta", "--clockwise", "--model", "single-track", "--plant", "double-track",
    "--speed", "7.25", "--laps", "2", "--max-time", "30.5", "--samples", "256", "--horizon", "60",
    "--iterations", "2", "--lambda", "4.5", "--noise-std", "0.2,0.45", "--smoothing", "9", "--seed", "12345678901", "--threads", "3",
    "--steer-rate-limit", "12.5", "--throttle-rate-limit", "7.5",
    "--backend", "cpu", "--cost-config", "my cost.yaml", "--cost-map", "map.npz", "--plant-params", "plant.yaml", "--model-params",
    "model.yaml", "--network", "net.npz", "--out", "out/x: y", "--json", "--quiet", "--data-dir", kDataDir};
const std::string kRunFile = R"(track: marietta
clockwise: true
model: single-track
plant: double-track
speed: 7.25
laps: 2
max-time: 30.5
samples: 256
horizon: 60
iterations: 2
lambda: 4.5
noise-std: 0.2,0.45
smoothing: 9
seed: 12345678901
steer-rate-limit: 12.5
throttle-rate-limit: 7.5
threads: 3
backend: cpu
cost-config: my cost.yaml
cost-map: map.npz
plant-params: plant.yaml
model-params: model.yaml
network: net.npz
out: "out/x: y"
json: true
quiet: true
data-dir: )" + kDataDir + "\n";

}  // namespace

TEST_CASE("cli: the flags set the configuration they name", "[cli]") {
  const SimCommandLine cl = parse_sim(kFlags);
  // An independent oracle: the values written by hand.
  SimCommandLine expected;
  mppi::sim::ClosedLoopConfig& c = expected.config;
  c.track = "marietta";
  c.clockwise = true;
  c.model = "single-track";
  c.plant = "double-track";
  c.target_speed_mps = 7.25;
  c.laps = 2;
  c.max_time_s = 30.5;
  c.controller.num_samples = 256;
  c.controller.horizon = 60;
  c.controller.iterations = 2;
  c.controller.lambda = 4.5f;
  c.controller.noise_std = {0.2f, 0.45f};
  c.controller.smoothing_window = 9;
  c.controller.seed = 12345678901ull;
  c.controller.num_threads = 3;
  c.actuators.steer_rate_per_s = 12.5f;
  c.actuators.throttle_rate_per_s = 7.5f;
  c.backend = mppi::BackendChoice::kCpu;
  c.cost_params_yaml = "my cost.yaml";
  c.cost_map_npz = "map.npz";
  c.plant_params_yaml = "plant.yaml";
  c.model_params_yaml = "model.yaml";
  c.network_npz = "net.npz";
  c.out_dir = "out/x: y";
  c.progress = false;
  expected.print_json = true;
  expected.quiet = true;
  expected.data_dir = kDataDir;
  require_same(cl, expected);
}

TEST_CASE("cli: no flags give mppi-sim's defaults", "[cli]") {
  const SimCommandLine cl = parse_sim({});
  SimCommandLine expected;
  expected.config = mppi::sim::ClosedLoopConfig{};
  expected.config.out_dir = "out/sim";
  expected.config.backend = mppi::BackendChoice::kAuto;
  expected.config.controller.smoothing_window = 5;  // upstream's plan smoothing
  require_same(cl, expected);
}

TEST_CASE("cli: a run file and the equivalent flags give the same configuration", "[cli]") {
  const TempFile file(kRunFile);
  const SimCommandLine from_flags = parse_sim(kFlags);
  const SimCommandLine from_file = parse_sim({"--config", file.str()});
  require_same(from_file, from_flags);
  CHECK(from_file.config.controller.seed == 12345678901ull);  // not the default: the file was read
}

TEST_CASE("cli: flags on the command line win over the run file", "[cli]") {
  const TempFile file(kRunFile);
  // Before and after --config: the position does not matter.
  for (const auto& args : {std::vector<std::string>{"--speed", "9", "--config", file.str(), "--track", "ccrf"},
                           std::vector<std::string>{"--config", file.str(), "--speed", "9", "--track", "ccrf"}}) {
    const SimCommandLine cl = parse_sim(args);
    CHECK(cl.config.target_speed_mps == 9.0);
    CHECK(cl.config.track == "ccrf");
    CHECK(cl.config.laps == 2);  // from the file
    CHECK(cl.config.controller.num_samples == 256);
  }
  // A flag set on the command line stays set when the file says false.
  const TempFile quiet_off("quiet: false\njson: false\n");
  const SimCommandLine cl = parse_sim({"--quiet", "--config", quiet_off.str()});
  CHECK(cl.quiet);
  CHECK_FALSE(cl.config.progress);
  CHECK_FALSE(cl.print_json);
}

TEST_CASE("cli: bad run-file keys and values are refused, naming the key and the file", "[cli]") {
  SECTION("unknown key") {
    const TempFile file("speed: 8\nsped: 9\n");
    const std::string msg = parse_error({"--config", file.str()});
    CHECK(msg.find("unknown key 'sped'") != std::string::npos);
    CHECK(msg.find(file.str()) != std::string::npos);
  }
  SECTION("a key of an action flag") {
    const TempFile file("dump-config: true\n");
    const std::string msg = parse_error({"--config", file.str()});
    CHECK(msg.find("unknown key 'dump-config'") != std::string::npos);
  }
  SECTION("a number that is not one") {
    const TempFile file("speed: fast\n");
    const std::string msg = parse_error({"--config", file.str()});
    CHECK(msg.find("key 'speed'") != std::string::npos);
    CHECK(msg.find(file.str()) != std::string::npos);
    CHECK(msg.find("fast") != std::string::npos);
  }
  SECTION("a name outside the choices") {
    const TempFile file("track: nowhere\n");
    const std::string msg = parse_error({"--config", file.str()});
    CHECK(msg.find("key 'track'") != std::string::npos);
    CHECK(msg.find("nowhere") != std::string::npos);
  }
  SECTION("a flag that is neither true nor false") {
    const TempFile file("clockwise: maybe\n");
    const std::string msg = parse_error({"--config", file.str()});
    CHECK(msg.find("key 'clockwise'") != std::string::npos);
    CHECK(msg.find("maybe") != std::string::npos);
  }
  SECTION("not a map") {
    const TempFile file("- speed\n- 8\n");
    CHECK(parse_error({"--config", file.str()}).find(file.str()) != std::string::npos);
  }
  SECTION("a file that does not exist") {
    CHECK(parse_error({"--config", "/nonexistent/run.yaml"}).find("/nonexistent/run.yaml") != std::string::npos);
  }
}

TEST_CASE("cli: bad flags and values on the command line are refused by name", "[cli]") {
  CHECK(parse_error({"--no-such-flag"}).find("--no-such-flag") != std::string::npos);
  CHECK(parse_error({"--laps", "two"}).find("--laps") != std::string::npos);
  CHECK(parse_error({"--model", "tricycle"}).find("--model") != std::string::npos);
  CHECK(parse_error({"--backend", "gpu"}).find("--backend") != std::string::npos);
  CHECK(parse_error({"--horizon", "1.5"}).find("--horizon") != std::string::npos);
  CHECK(parse_error({"--threads", "-2"}).find("--threads") != std::string::npos);
  CHECK(parse_error({"--speed", "7"}).empty());
  CHECK(parse_error({"--steer-rate-limit", "0"}).find("--steer-rate-limit") != std::string::npos);
  CHECK(parse_error({"--throttle-rate-limit", "-1"}).find("--throttle-rate-limit") != std::string::npos);
  // The default plan smoothing (5 steps) does not fit a 3-step horizon: the message says how out.
  const std::string short_horizon = parse_error({"--horizon", "3"});
  CHECK(short_horizon.find("--smoothing") != std::string::npos);
  CHECK(short_horizon.find("--smoothing 0") != std::string::npos);
  CHECK(parse_error({"--horizon", "3", "--smoothing", "0"}).empty());
  CHECK(parse_error({"--horizon", "3", "--smoothing", "3"}).empty());
}

TEST_CASE("cli: --dump-config round-trips", "[cli]") {
  for (const auto& args : {std::vector<std::string>{}, kFlags}) {
    std::string dump;
    const SimCommandLine original = parse_sim(args, &dump);
    const TempFile file(dump);
    std::string dump_again;
    const SimCommandLine reread = parse_sim({"--config", file.str()}, &dump_again);
    require_same(reread, original);
    CHECK(dump_again == dump);
  }
  // The dump holds every configurable flag as a key, and none of the action flags.
  std::string dump;
  parse_sim({}, &dump);
  for (const char* key : {"\ntrack: gazebo\n", "\nspeed: 6\n", "\nsamples: 1920\n", "\nbackend: auto\n",
                          "\nout: out/sim\n", "\nquiet: false\n", "\nclockwise: false\n"})
    CHECK(dump.find(key) != std::string::npos);
  for (const char* key : {"\nconfig:", "\ndump-config:", "\nlist-models:", "\nhelp:"})
    CHECK(dump.find(key) == std::string::npos);
}

TEST_CASE("cli: the shipped example run file is a valid mppi-sim configuration", "[cli]") {
  const SimCommandLine cl = parse_sim({"--config", mppi::test::data_path("config/run_example.yaml")});
  CHECK(cl.config.track == "gazebo");
  CHECK(cl.config.laps == 3);
}

TEST_CASE("cli: --limit-lap is a flag of the command line, the run file and --help", "[cli][limit_lap]") {
  CHECK_FALSE(parse_sim({}).limit_lap);
  CHECK(parse_sim({"--limit-lap"}).limit_lap);
  const TempFile file("limit-lap: true\ntrack: ccrf\n");
  const SimCommandLine cl = parse_sim({"--config", file.str()});
  CHECK(cl.limit_lap);
  CHECK(cl.config.track == "ccrf");
  CLI::App app{"", "mppi-sim"};
  SimCommandLine help;
  mppi::cli::add_sim_options(app, help);
  CHECK(app.help().find("--limit-lap") != std::string::npos);
}
