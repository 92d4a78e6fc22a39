#include <catch2/catch.hpp>

#include <functional>
#include <string>

#include "base/error.hpp"
#include "costs/cost_config.hpp"
#include "error_of.hpp"
#include "test_data.hpp"

namespace {
using mppi::test::error_of;
}  // namespace

TEST_CASE("Cost config: the shipped YAML holds the struct defaults", "[costs]") {
  const auto p = mppi::load_autorally_cost_params(mppi::test::data_path("config/autorally_cost.yaml"));
  const mppi::AutoRallyCostParams d;
  CHECK(p.track_weight == d.track_weight);
  CHECK(p.speed_weight == d.speed_weight);
  CHECK(p.crash_weight == d.crash_weight);
  CHECK(p.slip_weight == d.slip_weight);
  CHECK(p.target_speed_mps == d.target_speed_mps);
  CHECK(p.crash_discount == d.crash_discount);
  CHECK(p.boundary_threshold == d.boundary_threshold);
  CHECK(p.max_roll_rad == d.max_roll_rad);
  CHECK(p.max_yaw_rate_radps == d.max_yaw_rate_radps);
  CHECK(p.slip_min_speed_mps == d.slip_min_speed_mps);
  // The paper's weights, independently of the struct.
  CHECK(p.track_weight == 100.f);
  CHECK(p.speed_weight == 4.25f);
  CHECK(p.crash_weight == 10000.f);
  CHECK(p.slip_weight == 1.75f);
}

TEST_CASE("Cost config: partial YAML keeps defaults for missing keys", "[costs]") {
  const auto p = mppi::parse_autorally_cost_params("target_speed_mps: 8.5\nslip_weight: 0  # off\n");
  CHECK(p.target_speed_mps == 8.5f);
  CHECK(p.slip_weight == 0.f);
  CHECK(p.track_weight == 100.f);
  const auto empty = mppi::parse_autorally_cost_params("# nothing\n");
  CHECK(empty.crash_weight == 10000.f);
  CHECK(mppi::parse_autorally_cost_params("max_yaw_rate_radps: .inf").max_yaw_rate_radps > 1e30f);
}

TEST_CASE("Cost config: errors name the file, the key and its line", "[costs]") {
  std::string msg = error_of([] {
    (void)mppi::parse_autorally_cost_params("track_weight: 100\nspeed_weight: 4\n\nslip_wieght: 2\n", "my.yaml");
  });
  CHECK_THAT(msg, Catch::Contains("my.yaml:4:") && Catch::Contains("unknown key 'slip_wieght'"));

  msg = error_of([] { (void)mppi::parse_autorally_cost_params("track_weight: 100\nspeed_weight: fast\n", "t.yaml"); });
  CHECK_THAT(msg, Catch::Contains("t.yaml:2:") && Catch::Contains("speed_weight") && Catch::Contains("fast"));

  msg = error_of([] { (void)mppi::parse_autorally_cost_params("crash_weight: [1, 2]\n", "t.yaml"); });
  CHECK_THAT(msg, Catch::Contains("t.yaml:1:") && Catch::Contains("crash_weight"));

  msg = error_of([] { (void)mppi::parse_autorally_cost_params("a: 1\ntrack_weight: -5\n", "w.yaml"); });
  CHECK_THAT(msg, Catch::Contains("unknown key 'a'"));
  msg = error_of([] { (void)mppi::parse_autorally_cost_params("\ntrack_weight: -5\n", "w.yaml"); });
  CHECK_THAT(msg, Catch::Contains("w.yaml:2:") && Catch::Contains("track_weight"));

  msg = error_of([] { (void)mppi::parse_autorally_cost_params("slip_weight: .nan\n", "n.yaml"); });
  CHECK_THAT(msg, Catch::Contains("n.yaml:1:") && Catch::Contains("NaN"));

  msg = error_of([] { (void)mppi::parse_autorally_cost_params("crash_discount: 1.2\n", "d.yaml"); });
  CHECK_THAT(msg, Catch::Contains("crash_discount"));

  msg = error_of([] { (void)mppi::parse_autorally_cost_params("speed_weight: 1\nspeed_weight: 2\n", "dup.yaml"); });
  CHECK_THAT(msg, Catch::Contains("dup.yaml:2:") && Catch::Contains("twice"));

  msg = error_of([] { (void)mppi::parse_autorally_cost_params("- 1\n- 2\n", "list.yaml"); });
  CHECK_THAT(msg, Catch::Contains("list.yaml") && Catch::Contains("mapping"));

  msg = error_of([] { (void)mppi::parse_autorally_cost_params("speed_weight: [1\n", "syntax.yaml"); });
  CHECK_THAT(msg, Catch::Contains("syntax.yaml"));

  msg = error_of([] { (void)mppi::load_autorally_cost_params("/nonexistent/cost.yaml"); });
  CHECK_THAT(msg, Catch::Contains("/nonexistent/cost.yaml"));
}
