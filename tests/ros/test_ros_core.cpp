// The ROS nodes' ROS-free pieces: odometry <-> state, the safety monitor and its status, the
// timing report, the controller settings and the simulated car.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "mppi/controller_options.hpp"
#include "ros/chassis_convention.hpp"
#include "ros/controller_setup.hpp"
#include "ros/latency_stats.hpp"
#include "ros/odometry_state.hpp"
#include "ros/safety_monitor.hpp"
#include "ros/sim_car.hpp"

using namespace mppi;
using namespace mppi::ros;

TEST_CASE("odometry round-trips the common state, world twist turned into the body frame", "[ros]") {
  VehicleState s;
  s.x_m = 3.5f;
  s.y_m = -2.f;
  s.yaw_rad = 2.5f;
  s.vx_mps = 6.f;
  s.vy_mps = -0.4f;
  s.yaw_rate_radps = 0.7f;
  s.roll_rad = 0.05f;
  const OdometryFields o = odometry_from_state(s, 12.0);
  CHECK(o.stamp_s == 12.0);
  // The world velocity of a car heading 2.5 rad at 6 m/s points that way.
  CHECK(std::atan2(o.vy_world_mps, o.vx_world_mps) == Approx(2.5 + std::atan2(-0.4, 6.0)).margin(1e-6));
  VehicleState back;
  REQUIRE(state_from_odometry(o, &back));
  CHECK(back.x_m == Approx(3.5f));
  CHECK(back.y_m == Approx(-2.f));
  CHECK(back.yaw_rad == Approx(2.5f).margin(1e-6));
  CHECK(back.vx_mps == Approx(6.f).margin(1e-5));
  CHECK(back.vy_mps == Approx(-0.4f).margin(1e-5));
  CHECK(back.yaw_rate_radps == Approx(0.7f));
  CHECK(back.roll_rad == Approx(0.05f).margin(1e-6));
}

TEST_CASE("odometry with NaN or a non-unit quaternion is refused, naming the field", "[ros]") {
  OdometryFields o;
  VehicleState s;
  s.x_m = 42.f;
  const char* why = "";
  o.vx_world_mps = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(state_from_odometry(o, &s, &why));
  CHECK(std::string(why).find("twist.linear") != std::string::npos);
  CHECK(s.x_m == 42.f);
  o = OdometryFields{};
  o.qw = 0.0;
  CHECK_FALSE(state_from_odometry(o, &s, &why));
  CHECK(std::string(why).find("orientation") != std::string::npos);
}

TEST_CASE("the safety monitor: no pose, stale pose, runstop and errors give AutoRally's status", "[ros]") {
  SafetyMonitor m;  // pose timeout 0.5 s
  NodeStatus st = m.status(0.0);
  CHECK(st.level == StatusLevel::kWarning);
  CHECK(st.safe_stop);
  m.on_pose(1.0);
  st = m.status(1.2);
  CHECK(st.level == StatusLevel::kOk);
  CHECK_FALSE(st.safe_stop);
  CHECK_FALSE(m.pose_stale(1.5));
  st = m.status(1.51);  // older than 0.5 s
  CHECK_FALSE(m.may_step(1.51));
  CHECK(st.level == StatusLevel::kError);
  CHECK(st.info == "POSE STALE");
  CHECK(st.safe_stop);
  m.on_pose(2.0);
  m.on_runstop(false, 2.0);
  st = m.status(2.01);
  CHECK(st.level == StatusLevel::kWarning);
  CHECK(st.safe_stop);
  m.on_runstop(true, 2.02);
  CHECK_FALSE(m.status(2.03).safe_stop);
  m.on_step(false, "backend lost");
  st = m.status(2.04);
  CHECK(st.level == StatusLevel::kError);
  CHECK(st.info.find("backend lost") != std::string::npos);
  CHECK(st.safe_stop);
  CHECK(m.may_step(2.04));  // the next pose gets a new step, which may clear the error
  m.on_step(true);
  CHECK(m.status(2.05).level == StatusLevel::kOk);
}

TEST_CASE("with require_runstop, motion needs a fresh runstop message", "[ros]") {
  SafetySettings settings;
  settings.require_runstop = true;
  SafetyMonitor m(settings);
  m.on_pose(0.0);
  CHECK(m.status(0.1).safe_stop);  // none heard
  m.on_runstop(true, 0.1);
  CHECK_FALSE(m.status(0.2).safe_stop);
  CHECK(m.motion_allowed(1.05));  // the runstop of 0.1 s counts for 1 s
  CHECK_FALSE(m.motion_allowed(1.2));
  m.on_pose(1.15);  // a fresh pose: the stop is the runstop's
  const NodeStatus st = m.status(1.2);
  CHECK(st.safe_stop);
  CHECK(st.level == StatusLevel::kWarning);
  CHECK(st.info.find("no runstop") != std::string::npos);
  std::string why;
  settings.pose_timeout_s = 0.0;
  CHECK_FALSE(settings.is_valid(&why));
  CHECK(why.find("pose_timeout_s") != std::string::npos);
}

TEST_CASE("timing stats give latency percentiles and a JSON report", "[ros]") {
  TimingStats t;
  CHECK(std::isnan(t.latency_ms_percentile(99)));
  for (int i = 1; i <= 100; ++i) t.add_latency_ms(i);
  t.count_safe_stop();
  CHECK(t.commands() == 100);
  CHECK(t.latency_ms_percentile(50) == Approx(50.5));
  CHECK(t.latency_ms_percentile(99) == Approx(99.01));
  const std::string j = t.to_json();
  CHECK(j.find("\"commands\": 100") != std::string::npos);
  CHECK(j.find("\"p99\": 99.0100") != std::string::npos);
  CHECK(j.find("\"safe_stops\": 1") != std::string::npos);
  CHECK_THROWS_WITH(t.write_json("/nonexistent-dir/x.json"), Catch::Contains("/nonexistent-dir/x.json"));
}

TEST_CASE("controller node settings map AutoRally's parameter names onto the options", "[ros]") {
  ControllerNodeSettings s;
  s.hz = 40.0;
  s.num_timesteps = 60;
  s.num_rollouts = 256;
  s.steering_std = 0.2;
  s.max_throttle = 0.5;
  s.variant = "tube";
  std::string why;
  REQUIRE(s.is_valid(&why));
  const ControllerOptions o = s.options();
  CHECK(o.dt_s == Approx(0.025f));
  CHECK(o.horizon == 60);
  CHECK(o.num_samples == 256);
  CHECK(o.noise_std[0] == Approx(0.2f));
  CHECK(o.control_max[1] == Approx(0.5f));
  CHECK(o.variant == ControllerVariant::kTube);
  s.variant = "wobbly";
  CHECK_FALSE(s.is_valid(&why));
  CHECK(why.find("variant") != std::string::npos);
  s.variant = "plain";
  s.backend = "cuda";
  CHECK_FALSE(s.is_valid(&why));
  CHECK(why.find("backend") != std::string::npos);
  s.backend = "cpu";
  s.serve_port = 70000;
  CHECK_FALSE(s.is_valid(&why));
  CHECK(why.find("serve_port") != std::string::npos);
  s.serve_port = -1;
  s.hz = 0.0;
  CHECK_FALSE(s.is_valid(&why));
  CHECK(why.find("hz") != std::string::npos);
  s.hz = 50.0;
  s.model = "tricycle";
  CHECK_THROWS_WITH(NodeController(s), Catch::Contains("tricycle"));
}

TEST_CASE("a node controller steps on a state read from odometry", "[ros]") {
  ControllerNodeSettings s;
  s.model = "single-track";
  s.num_rollouts = 64;
  s.num_timesteps = 30;
  s.num_threads = 1;
  s.variant = "tube";
  NodeController c(s);
  SimCar car(SimCarSettings{});
  VehicleState st;
  REQUIRE(state_from_odometry(odometry_from_state(car.state(), 0.0), &st));
  const NodeController::Step step = c.step(st);
  CHECK(step.ok);
  CHECK(std::isfinite(step.output.steer));
  CHECK(step.output.throttle > 0.f);  // at rest on the start line, it drives off
  CHECK(c.feedback_gains().size() == static_cast<std::size_t>(30 * 2 * c.model_states()));
  std::vector<float> xy;
  c.planned_path(&xy);
  REQUIRE(xy.size() == 31 * 2);
  CHECK(xy[0] == Approx(st.x_m));
}

TEST_CASE("the simulated car waits, drives on commands, and its steering delay holds the steering back", "[ros]") {
  SimCarSettings settings;
  settings.steering_delay_s = 0.08;
  SimCar car(settings);
  const VehicleState s0 = car.state();
  car.command({0.5f, 0.3f}, 0.0);
  car.advance_to(0.07);
  CHECK(car.applied().steer == 0.f);  // not yet: 0.08 s delay
  CHECK(car.applied().throttle > 0.f);
  for (int i = 1; i <= 5; ++i) {  // a controller at 50 Hz
    car.command({0.5f, 0.3f}, car.time_s());
    car.advance_to(0.07 + 0.02 * i);
  }
  CHECK(car.applied().steer > 0.f);
  const VehicleState s1 = car.state();
  CHECK(std::hypot(s1.x_m - s0.x_m, s1.y_m - s0.y_m) > 0.01);
  CHECK(car.crashes() == 0);
  CHECK(car.summary_json().find("\"laps\": 0") != std::string::npos);
  settings.plant_dt_s = 0.0;
  CHECK_THROWS_WITH(SimCar(settings), Catch::Contains("plant_dt_s"));
}

TEST_CASE("the simulated car's steering rate limit: 5 /s by default, at once when raised", "[ros]") {
  SimCarSettings settings;
  SimCar limited(settings);
  limited.command({1.f, 0.f}, 0.0);
  limited.advance_to(0.02);
  CHECK(limited.applied().steer == Approx(0.1f).margin(0.011f));  // 5 /s x 0.02 s
  settings.steering_rate_per_s = settings.throttle_rate_per_s = 1e4;
  SimCar fast(settings);
  fast.command({1.f, 0.5f}, 0.0);
  fast.advance_to(0.02);
  CHECK(fast.applied().steer == Approx(1.f));
  CHECK(fast.applied().throttle == Approx(0.5f));
  settings.steering_rate_per_s = 0.0;
  CHECK_THROWS_WITH(SimCar(settings), Catch::Contains("steering_rate_per_s"));
}

TEST_CASE("the simulated car's chassis neutralises the throttle when commands stop (watchdog)", "[ros]") {
  SimCar car(SimCarSettings{});
  car.command({0.f, 0.5f}, 0.0);
  car.advance_to(0.05);
  CHECK(car.applied().throttle > 0.f);
  car.advance_to(1.0);  // no command for a second
  CHECK(car.applied().throttle == Approx(0.f).margin(1e-6));
}

TEST_CASE("AutoRally's chassis steering (+1 right) turns the simulated car the right way", "[ros]") {
  // A chassis command of -0.5 is half left in AutoRally's convention: the car's yaw must grow
  // (counter-clockwise), and the applied steering read back onto a chassis message is -0.5 again.
  SimCarSettings settings;
  SimCar car(settings);
  const double yaw0 = car.state().yaw_rad;
  for (int i = 1; i <= 75; ++i) {
    car.command({static_cast<float>(library_steer_from_chassis(-0.5)), 0.4f}, car.time_s());
    car.advance_to(0.02 * i);
  }
  CHECK(car.state().yaw_rad - yaw0 > 0.1);
  CHECK(chassis_steering_from_library(car.applied().steer) == Approx(-0.5));
  CHECK(library_steer_from_chassis(chassis_steering_from_library(0.25)) == 0.25);
}
