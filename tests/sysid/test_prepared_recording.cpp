// The prepared recording (sysid/prepared_recording.hpp) that calibration, estimation and diagnosis
// all read: its columns beyond the required ones, and its command timing, which the calibration's
// rollouts and the filter now take from it.
#include <algorithm>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "dynamics/vehicle_params.hpp"
#include "error_of.hpp"
#include "sysid/manoeuvre_rollout.hpp"
#include "sysid/plant_calibration.hpp"
#include "sysid/prepared_recording.hpp"

namespace {

using namespace mppi;
using namespace mppi::sysid;
using mppi::test::error_of;

std::vector<double>& column(sim::Recording& rec, const std::string& name) {
  const auto c = std::find(rec.columns.begin(), rec.columns.end(), name);
  REQUIRE(c != rec.columns.end());
  return rec.data[static_cast<std::size_t>(c - rec.columns.begin())];
}

// 8 s of the scripted manoeuvres driven by a single-track plant with a 0.1-s steering lag, the
// command of row k acting over (t[k], t[k+1]] (the rollout's own timing).
sim::Recording lagged_plant_drive(const VehicleModelSpec& spec, const std::vector<double>& lag) {
  const RolloutStep step = [&](std::vector<double>& x, const double u[2], double dt) { spec.step(lag, x.data(), u, dt); };
  ManoeuvreOptions o;
  o.duration_s = 8;
  o.ff_offset = 0.04;
  o.ff_per_mps = 0.05;
  o.extra_state_columns = {"omega_front", "omega_rear"};
  std::vector<double> x0(11, 0.0);
  x0[3] = 5.0;
  x0[7] = x0[8] = 5.0 / SingleTrackParams{}.wheel_radius_m;
  return roll_out_manoeuvres(step, x0, o);
}

}  // namespace

TEST_CASE("prepared recording: other columns travel with the rows, a missing one is named", "[sysid]") {
  const VehicleModelSpec spec = single_track_spec(SingleTrackParams{}, {"steer_lag_s"});
  const PreparedRecording d = prepare(lagged_plant_drive(spec, {0.1}), "drive.csv", 3);
  REQUIRE(d.has_column("omega_front"));
  REQUIRE(d.has_column("segment"));
  CHECK(&d.column("vx") == &d.vx);
  CHECK(!d.has_column("roll") == d.roll.empty());
  CHECK_THAT(error_of([&] { d.column("wheel_speed"); }),
             Catch::Contains("drive.csv") && Catch::Contains("'wheel_speed'"));

  const PreparedRecording part = slice_rows(d, 100, 200);
  REQUIRE(part.column("omega_front").size() == 100);
  CHECK(part.column("omega_front")[0] == d.column("omega_front")[100]);
  // Joined: only the columns both recordings have.
  PreparedRecording other = part;
  other.other_columns.erase("omega_front");
  const PreparedRecording both = concat(part, other);
  CHECK(!both.has_column("omega_front"));
  REQUIRE(both.has_column("omega_rear"));
  CHECK(both.column("omega_rear").size() == 200);
  CHECK(both.column("omega_rear")[150] == part.column("omega_rear")[50]);
}

TEST_CASE("prepared recording: calibration reads the commands with the recording's timing", "[sysid][calibration]") {
  // The same drive written as the simulator writes its logs: row k + 1 holds the command that
  // acted over (t[k], t[k+1]]. Declared as such (source: mppi-sim), the plant predicts it exactly;
  // read as a real recording (the command sent at t[k] acts after it), every command comes one
  // row late and the prediction fails.
  const VehicleModelSpec spec = single_track_spec(SingleTrackParams{}, {"steer_lag_s"});
  const std::vector<double> lag = {0.1};
  sim::Recording rec = lagged_plant_drive(spec, lag);
  for (const char* name : {"steer", "throttle"}) {
    std::vector<double>& u = column(rec, name);
    u.insert(u.begin(), 0.0);
    u.pop_back();
  }
  rec.metadata["source"] = "mppi-sim";
  const PreparedRecording as_logged = prepare(rec, "sim_log.csv", 3);
  REQUIRE(as_logged.control_lead == 1);
  const std::vector<double> scales = channel_scales(as_logged, {"vx", "vy", "yaw_rate"});
  const PredictionError logged = prediction_error(spec, lag, as_logged, scales);
  CHECK(logged.rollouts == 13);  // rows 25, 50, .., 325: after the first row, 1-s windows inside 400 rows
  CHECK(logged.mean_nrmse < 1e-3);

  rec.metadata.erase("source");
  const PreparedRecording as_real = prepare(rec, "real.csv", 3);
  REQUIRE(as_real.control_lead == 0);
  CHECK(prediction_error(spec, lag, as_real, scales).mean_nrmse > 0.01);
}
