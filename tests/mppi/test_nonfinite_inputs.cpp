// NaN and inf inside well-formed files are refused when the file is loaded, and the message
// names the file and the field (array or key): cost maps, network weights, vehicle and cost
// parameters. Fixtures: tests/data/npz/make_fixtures.py (numpy) and YAML written here.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "costs/cost_config.hpp"
#include "dynamics/autorally_nn.hpp"
#include "dynamics/vehicle_params.hpp"
#include "mppi/cost_map.hpp"
#include "tests/error_of.hpp"

using mppi::test::error_of;

namespace {

std::string fixture(const std::string& name) {
  return (std::filesystem::path(__FILE__).parent_path().parent_path() / "data" / "npz" / name).string();
}

std::string write_temp(const std::string& tag, const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("mppi_nonfinite_" + std::to_string(::getpid()) + "_" + tag + ".yaml")).string();
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST_CASE("a cost map with a NaN or inf cell is refused, naming file, array and cell", "[costs][nonfinite]") {
  const std::string nan_file = fixture("costmap_nan.npz");
  std::string msg = error_of([&] { (void)mppi::CostMap::load_npz(nan_file); });
  CHECK_THAT(msg, Catch::StartsWith(nan_file) && Catch::Contains("'channel0'") && Catch::Contains("NaN") &&
                      Catch::Contains("row 1, col 1"));
  const std::string inf_file = fixture("costmap_inf.npz");
  msg = error_of([&] { (void)mppi::CostMap::load_npz(inf_file); });
  CHECK_THAT(msg, Catch::StartsWith(inf_file) && Catch::Contains("'channel0'") && Catch::Contains("row 0, col 3"));
}

TEST_CASE("network weights with NaN, or a double that overflows a float, are refused by array", "[nn][nonfinite]") {
  const std::string nan_file = fixture("autorally_nan.npz");
  CHECK_THAT(error_of([&] { (void)mppi::AutoRallyNetwork::load(nan_file); }),
             Catch::StartsWith(nan_file) && Catch::Contains("'dynamics_b2'") && Catch::Contains("non-finite"));
  const std::string big_file = fixture("autorally_overflow.npz");
  CHECK_THAT(error_of([&] { (void)mppi::AutoRallyNetwork::load(big_file); }),
             Catch::StartsWith(big_file) && Catch::Contains("'dynamics_W3'") && Catch::Contains("non-finite"));
}

TEST_CASE("vehicle parameters with .nan, .inf or an overflowing number are refused by key and line", "[dynamics][nonfinite]") {
  for (const char* bad : {".nan", ".inf", "-.inf", "1e999"}) {
    INFO(bad);
    const std::string path = write_temp("vehicle", std::string("mass_kg: 21.88\nyaw_inertia_kgm2: ") + bad + "\n");
    const std::string msg = error_of([&] { (void)mppi::load_single_track_params(path); });
    CHECK_THAT(msg, Catch::StartsWith(path + ":2:") && Catch::Contains("yaw_inertia_kgm2"));
    std::filesystem::remove(path);
  }
  // A nested key (the tyre table) is named too.
  const std::string path = write_temp("tyre", "tyre:\n  B: 1.2\n  D: .nan\n");
  CHECK_THAT(error_of([&] { (void)mppi::load_single_track_params(path); }),
             Catch::StartsWith(path + ":3:") && Catch::Contains("D"));
  std::filesystem::remove(path);
}

TEST_CASE("cost parameters with .nan or .inf are refused by key and line", "[costs][nonfinite]") {
  for (const char* bad : {".nan", ".inf"}) {
    INFO(bad);
    const std::string path = write_temp("cost", std::string("target_speed_mps: 6\nslip_weight: ") + bad + "\n");
    CHECK_THAT(error_of([&] { (void)mppi::load_autorally_cost_params(path); }),
               Catch::StartsWith(path + ":2:") && Catch::Contains("slip_weight"));
    std::filesystem::remove(path);
  }
}
