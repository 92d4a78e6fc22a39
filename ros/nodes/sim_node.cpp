// mppi_sim_node: the built-in simulator as a ROS 1 node. The single-track car on a built-in
// track, behind the simulated chassis (priorities, runstop, watchdog, calibration) and
// rate-limited actuators (~steering_rate_per_s, ~throttle_rate_per_s) with optional pure delays
// (~steering_delay_s, ~throttle_delay_s),
// integrated in real time. Publishes /pose_estimate (nav_msgs/Odometry, AutoRally's convention:
// world-frame twist) and chassisState at ~rate_hz; drives on chassisCommand, stops on runstop.
// The car waits at the start line until the first command that asks for motion; laps are timed
// from then. With
// ~laps > 0 it writes its summary (laps, lap times, crashes) to ~summary_file and exits after
// that many laps. Nothing thrown leaves a callback.
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <autorally_msgs/chassisCommand.h>
#include <autorally_msgs/chassisState.h>
#include <autorally_msgs/runstop.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include "ros/chassis_convention.hpp"
#include "ros/nodes/node_params.hpp"
#include "ros/nodes/ros_messages.hpp"
#include "ros/sim_car.hpp"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

using mppi::ros::read_param;

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "mppi_sim", ros::init_options::NoSigintHandler);
  ros::NodeHandle nh("~"), pub_nh;
  mppi::ros::SimCarSettings settings;
  double rate_hz = 50.0, integration_hz = 500.0, max_time_s = 0.0;
  int laps = 0;
  std::string summary_file, pose_topic = "/pose_estimate", frame_id = "map";
  std::optional<mppi::ros::SimCar> car;
  try {
    read_param(nh, "track", settings.track);
    read_param(nh, "plant_params", settings.plant_params);
    read_param(nh, "plant_dt_s", settings.plant_dt_s);
    read_param(nh, "steering_delay_s", settings.steering_delay_s);
    read_param(nh, "throttle_delay_s", settings.throttle_delay_s);
    read_param(nh, "steering_rate_per_s", settings.steering_rate_per_s);
    read_param(nh, "throttle_rate_per_s", settings.throttle_rate_per_s);
    read_param(nh, "rate_hz", rate_hz);
    read_param(nh, "integration_hz", integration_hz);
    read_param(nh, "laps", laps);
    read_param(nh, "max_time_s", max_time_s);
    read_param(nh, "summary_file", summary_file);
    read_param(nh, "pose_estimate", pose_topic);
    read_param(nh, "frame_id", frame_id);
    if (!(rate_hz > 0.0 && rate_hz <= 1000.0)) throw std::runtime_error("rate_hz must be in (0, 1000]");
    if (!(integration_hz >= rate_hz && integration_hz <= 5000.0))
      throw std::runtime_error("integration_hz must be in [rate_hz, 5000]");
    car.emplace(settings);
  } catch (const std::exception& e) {
    ROS_FATAL("mppi_sim_node: %s", e.what());
    return 1;
  }
  ros::Publisher pose_pub = pub_nh.advertise<nav_msgs::Odometry>(pose_topic, 1);
  ros::Publisher state_pub = pub_nh.advertise<autorally_msgs::chassisState>("chassisState", 1);

  // The callbacks queue; the loop feeds the car (one thread touches it).
  std::mutex mutex;
  std::optional<mppi::Control> command;
  std::optional<bool> motion_enabled;
  ros::Subscriber command_sub = pub_nh.subscribe<autorally_msgs::chassisCommand>(
      "chassisCommand", 5, [&](const autorally_msgs::chassisCommand::ConstPtr& m) {
        try {
          const std::lock_guard<std::mutex> lock(mutex);
          command = mppi::Control{static_cast<float>(mppi::ros::library_steer_from_chassis(m->steering)),
                                  static_cast<float>(m->throttle)};
        } catch (const std::exception& e) {
          ROS_ERROR_THROTTLE(1.0, "mppi_sim_node: command callback: %s", e.what());
        }
      }, ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  ros::Subscriber runstop_sub = pub_nh.subscribe<autorally_msgs::runstop>(
      "runstop", 5, [&](const autorally_msgs::runstop::ConstPtr& m) {
        const std::lock_guard<std::mutex> lock(mutex);
        motion_enabled = static_cast<bool>(m->motionEnabled);
      });
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  ros::AsyncSpinner spinner(1);
  spinner.start();
  ROS_INFO("mppi_sim_node: single-track car on %s, poses at %.0f Hz on %s, steering delay %.3f s",
           settings.track.c_str(), rate_hz, pose_topic.c_str(), settings.steering_delay_s);

  using Clock = std::chrono::steady_clock;
  const auto tick = std::chrono::duration<double>(1.0 / integration_hz);
  const int publish_every = std::max(1, static_cast<int>(std::lround(integration_hz / rate_hz)));
  std::optional<Clock::time_point> t0;  // the first command
  auto next = Clock::now();
  long ticks = 0;
  int rc = 0;
  autorally_msgs::chassisState cs;
  try {
    while (ros::ok() && !g_stop) {
      std::optional<mppi::Control> u;
      {
        const std::lock_guard<std::mutex> lock(mutex);
        u.swap(command);
        if (motion_enabled) car->set_motion_enabled(*motion_enabled);
      }
      const auto now = Clock::now();
      // The clock starts with the first command that asks for motion (a controller's neutral
      // commands while it waits for its first pose leave the car at rest, untimed).
      if (u && !t0 && (u->steer != 0.f || u->throttle != 0.f)) t0 = now;
      if (t0) {
        const double t = std::chrono::duration<double>(now - *t0).count();
        car->advance_to(t);
        if (u) car->command(*u, car->time_s());
      }
      if (ticks % publish_every == 0) {
        const nav_msgs::Odometry odom = mppi::ros::odometry_msg(car->state(), ros::Time::now(), frame_id);
        pose_pub.publish(odom);
        cs.header.stamp = odom.header.stamp;
        cs.throttleRelayEnabled = true;
        cs.autonomousEnabled = true;
        cs.runstopMotionEnabled = car->motion_enabled();
        cs.steeringCommander = car->steering_commander();
        cs.throttleCommander = car->throttle_commander();
        cs.frontBrakeCommander = cs.throttleCommander;
        cs.steering = mppi::ros::chassis_steering_from_library(car->applied().steer);
        cs.throttle = car->applied().throttle;
        cs.frontBrake = 0.0;
        state_pub.publish(cs);
      }
      ++ticks;
      if (laps > 0 && car->laps_completed() >= laps) break;
      if (max_time_s > 0.0 && car->time_s() >= max_time_s) break;
      next += std::chrono::duration_cast<Clock::duration>(tick);
      if (next < Clock::now() - std::chrono::milliseconds(100)) next = Clock::now();  // fell far behind
      std::this_thread::sleep_until(next);
    }
  } catch (const std::exception& e) {
    ROS_ERROR("mppi_sim_node: %s", e.what());
    rc = 1;
  }
  spinner.stop();
  const std::string summary = car->summary_json();
  std::fprintf(stderr, "mppi_sim_node: %s", summary.c_str());
  if (!summary_file.empty()) {
    std::ofstream out(summary_file);
    out << summary;
    if (!out) {
      std::fprintf(stderr, "mppi_sim_node: cannot write the summary to %s\n", summary_file.c_str());
      rc = 1;
    }
  }
  ros::shutdown();
  return rc;
}
