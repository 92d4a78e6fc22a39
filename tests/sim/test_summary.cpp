// Run summary JSON and the percentile helper (oracle: numpy.percentile, default 'linear').
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include <nlohmann/json.hpp>
#include <unistd.h>

#include "base/error.hpp"
#include "sim/summary.hpp"

using namespace mppi::sim;

TEST_CASE("percentile matches numpy.percentile", "[sim]") {
  const std::vector<double> v{3.2, 1.5, 9.75, 4.0, 2.25, 7.5, 0.5};
  // python: np.percentile(v, p)
  CHECK(percentile(v, 0) == Approx(0.5));
  CHECK(percentile(v, 10) == Approx(1.1));
  CHECK(percentile(v, 25) == Approx(1.875));
  CHECK(percentile(v, 50) == Approx(3.2));
  CHECK(percentile(v, 90) == Approx(8.4));
  CHECK(percentile(v, 99) == Approx(9.614999999999998));
  CHECK(percentile(v, 100) == Approx(9.75));
  CHECK(percentile({5.0, 1.0}, 50) == Approx(3.0));
  CHECK(percentile({5.0, 1.0}, 99) == Approx(4.96));
  CHECK(percentile({42.0}, 37) == 42.0);
  CHECK(std::isnan(percentile({}, 50)));
  CHECK_THROWS_AS(percentile(v, 101), mppi::Error);
  CHECK_THROWS_AS(percentile(v, -1), mppi::Error);
  CHECK_THROWS_AS(percentile(v, std::nan("")), mppi::Error);
}

TEST_CASE("run summary JSON has every field, NaN as null", "[sim]") {
  RunSummary s;
  s.track = "gazebo";
  s.model = "nn_autorally";
  s.plant = "single_track";
  s.seed = 1234567890123ULL;
  s.samples = 1920;
  s.horizon = 100;
  s.target_speed_mps = 6.0;
  s.sim_time_s = 60.0;
  s.finished = true;
  s.laps_completed = 2;
  s.lap_times_s = {12.5, 11.75};
  s.limit_lap_s = 6.25;
  s.standing_limit_lap_s = 7.8125;
  s.limit_lap_method = "collocation";
  s.lap_time_ratio = {1.6, 1.88};  // lap 1 over the standing-start limit lap
  s.crashes = 1;
  s.crash_reasons = {"hit the outer barrier at (1.00, 2.00)"};
  s.stalls = 1;
  s.stall_times_s = {31.5};
  s.mean_speed_mps = 5.5;
  s.max_speed_mps = 7.25;
  s.optimizer_ms_p50 = 1.5;
  s.optimizer_ms_p99 = std::numeric_limits<double>::quiet_NaN();
  s.effective_sample_size_mean = 42.5;
  s.peak_slip_angle_rad = 0.25;
  s.p95_slip_angle_rad = 0.125;
  s.peak_lateral_accel_mps2 = 6.5;
  s.sampler = "smooth";
  s.ess_target_share = 0.125;
  s.lambda_p50 = 3.5;
  s.actuator_model = "plant";
  s.variant = "tube";
  s.nominal_resets = 7;
  s.mean_abs_steer_step = 0.0625;
  s.mean_abs_throttle_step = 0.03125;
  s.lateral_force_adaptation = true;
  s.lateral_force_scale_final = 0.625;
  s.lateral_force_scale_p50 = 0.75;
  const auto j = nlohmann::json::parse(to_json(s));
  CHECK(j.size() == 42);
  CHECK(j.at("lateral_force_adaptation") == true);
  CHECK(j.at("lateral_force_scale_final") == 0.625);
  CHECK(j.at("lateral_force_scale_p50") == 0.75);
  CHECK(j.at("limit_lap_method") == "collocation");
  CHECK(nlohmann::json::parse(to_json(RunSummary{})).at("limit_lap_method").is_null());
  CHECK(j.at("variant") == "tube");
  CHECK(j.at("nominal_resets") == 7);
  CHECK(j.at("sampler") == "smooth");
  CHECK(j.at("ess_target_share") == 0.125);
  CHECK(j.at("ess_in_band_share").is_null());  // NaN: a fixed temperature
  CHECK(j.at("lambda_p50") == 3.5);
  CHECK(j.at("actuator_model") == "plant");
  CHECK(j.at("track") == "gazebo");
  CHECK(j.at("model") == "nn_autorally");
  CHECK(j.at("plant") == "single_track");
  CHECK(j.at("seed").get<std::uint64_t>() == 1234567890123ULL);
  CHECK(j.at("samples") == 1920);
  CHECK(j.at("horizon") == 100);
  CHECK(j.at("target_speed_mps") == 6.0);
  CHECK(j.at("sim_time_s") == 60.0);
  CHECK(j.at("finished") == true);
  CHECK(j.at("laps_completed") == 2);
  CHECK(j.at("lap_times_s") == nlohmann::json::array({12.5, 11.75}));
  CHECK(j.at("limit_lap_s") == 6.25);
  CHECK(j.at("standing_limit_lap_s") == 7.8125);
  CHECK(nlohmann::json::parse(to_json(RunSummary{})).at("standing_limit_lap_s").is_null());
  CHECK(j.at("lap_time_ratio") == nlohmann::json::array({1.6, 1.88}));
  CHECK(j.at("crashes") == 1);
  CHECK(j.at("crash_reasons")[0] == "hit the outer barrier at (1.00, 2.00)");
  CHECK(j.at("stalls") == 1);
  CHECK(j.at("stall_times_s") == nlohmann::json::array({31.5}));
  CHECK(j.at("mean_speed_mps") == 5.5);
  CHECK(j.at("max_speed_mps") == 7.25);
  CHECK(j.at("optimizer_ms_p50") == 1.5);
  CHECK(j.at("optimizer_ms_p99").is_null());
  CHECK(j.at("mean_abs_steer_step") == 0.0625);
  CHECK(j.at("mean_abs_throttle_step") == 0.03125);
  CHECK(j.at("effective_sample_size_mean") == 42.5);
  CHECK(j.at("peak_slip_angle_rad") == 0.25);
  CHECK(j.at("p95_slip_angle_rad") == 0.125);
  CHECK(j.at("peak_lateral_accel_mps2") == 6.5);

  const std::string path = (std::filesystem::temp_directory_path() /
                            ("mppi_sim_test_summary_" + std::to_string(::getpid()) + ".json")).string();
  write_summary(path, s);
  std::ifstream in(path);
  CHECK(nlohmann::json::parse(in) == j);
  in.close();
  std::filesystem::remove(path);
  CHECK_THROWS_AS(write_summary("/nonexistent-dir/summary.json", s), mppi::Error);
}
