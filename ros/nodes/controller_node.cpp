// mppi_controller_node: MPPI as a ROS 1 node, a drop-in for AutoRally's path-integral node.
// Subscribes /pose_estimate (nav_msgs/Odometry), chassisState and runstop; publishes
// chassisCommand, nominalPath (nav_msgs/Path), pathIntegralStatus, pathIntegralTiming and, for
// the tube and robust variants, feedbackGains (std_msgs/Float32MultiArray, T x nu x nx).
// A step runs as soon as a pose comes (at most `hz` times a second); the loop also wakes once
// a control period without poses, so that a stale pose (older than pose_timeout_s) or a runstop
// brings the safe stop (steering 0, throttle 0) within one period. Nothing thrown leaves a
// callback or the loop: errors are reported in pathIntegralStatus (status 2) and stop the car.
// On exit it writes the timing (odometry-to-command latency percentiles) to ~stats_file.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <autorally_msgs/chassisCommand.h>
#include <autorally_msgs/chassisState.h>
#include <autorally_msgs/pathIntegralStatus.h>
#include <autorally_msgs/pathIntegralTiming.h>
#include <autorally_msgs/runstop.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_msgs/Float32MultiArray.h>

#include "base/error.hpp"
#include "ros/chassis_convention.hpp"
#include "ros/controller_setup.hpp"
#include "ros/latency_stats.hpp"
#include "ros/odometry_state.hpp"
#include "ros/nodes/node_params.hpp"
#include "ros/nodes/ros_messages.hpp"
#include "ros/safety_monitor.hpp"

namespace {

using mppi::ros::OdometryFields;

// What the callbacks hand to the control loop.
struct Inbox {
  std::mutex mutex;
  std::condition_variable wake;
  std::optional<OdometryFields> pose;  // a pose not yet used
  double pose_arrival_s = 0.0;
  std::optional<std::pair<bool, double>> runstop;  // motionEnabled, arrival
  bool runstop_changed = false;
};

double now_s() { return ros::Time::now().toSec(); }

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }  // the loop ends within a control period

using mppi::ros::read_param;

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "mppi_controller", ros::init_options::NoSigintHandler);
  ros::NodeHandle nh("~"), pub_nh;
  mppi::ros::ControllerNodeSettings s;
  mppi::ros::SafetySettings safety;
  std::string pose_topic = "/pose_estimate", stats_file, sender = "mppi_controller";
  int seed = 1, path_every = 1;
  try {
    read_param(nh, "hz", s.hz);
    read_param(nh, "num_timesteps", s.num_timesteps);
    read_param(nh, "num_rollouts", s.num_rollouts);
    read_param(nh, "desired_speed", s.desired_speed);
    read_param(nh, "track", s.track);
    read_param(nh, "map_path", s.map_path);
    read_param(nh, "cost_params", s.cost_params);
    read_param(nh, "steering_std", s.steering_std);
    read_param(nh, "throttle_std", s.throttle_std);
    read_param(nh, "gamma", s.gamma);
    read_param(nh, "lambda", s.lambda);
    read_param(nh, "max_throttle", s.max_throttle);
    read_param(nh, "max_steering", s.max_steering);
    read_param(nh, "model", s.model);
    read_param(nh, "model_params", s.model_params);
    read_param(nh, "backend", s.backend);
    read_param(nh, "variant", s.variant);
    read_param(nh, "adapt_grip", s.adapt_grip);
    read_param(nh, "robust_augmented", s.robust_augmented);
    read_param(nh, "robust_cost_bound", s.robust_cost_bound);
    read_param(nh, "num_threads", s.num_threads);
    read_param(nh, "seed", seed);
    s.seed = static_cast<std::uint64_t>(seed);
    read_param(nh, "pose_estimate", pose_topic);
    read_param(nh, "pose_timeout_s", safety.pose_timeout_s);
    read_param(nh, "require_runstop", safety.require_runstop);
    read_param(nh, "runstop_timeout_s", safety.runstop_timeout_s);
    read_param(nh, "stats_file", stats_file);
    read_param(nh, "path_every", path_every);
    read_param(nh, "serve_port", s.serve_port);
    std::string why;
    if (!safety.is_valid(&why)) throw mppi::Error("controller node parameters: " + why);
  } catch (const std::exception& e) {
    ROS_FATAL("mppi_controller_node: %s", e.what());
    return 1;
  }

  std::unique_ptr<mppi::ros::NodeController> controller;
  try {
    controller = std::make_unique<mppi::ros::NodeController>(s);
  } catch (const std::exception& e) {
    ROS_FATAL("mppi_controller_node: %s", e.what());
    return 1;
  }
  ROS_INFO("mppi_controller_node: %s MPPI (%s, K = %d, T = %d) at %.0f Hz on %s; backend %s", s.model.c_str(),
           s.variant.c_str(), s.num_rollouts, s.num_timesteps, s.hz, pose_topic.c_str(), controller->backend().c_str());

  ros::Publisher command_pub = pub_nh.advertise<autorally_msgs::chassisCommand>("chassisCommand", 1);
  ros::Publisher path_pub = pub_nh.advertise<nav_msgs::Path>("nominalPath", 1);
  ros::Publisher status_pub = pub_nh.advertise<autorally_msgs::pathIntegralStatus>("pathIntegralStatus", 1);
  ros::Publisher timing_pub = pub_nh.advertise<autorally_msgs::pathIntegralTiming>("pathIntegralTiming", 1);
  ros::Publisher gains_pub;
  if (s.variant != "plain") gains_pub = pub_nh.advertise<std_msgs::Float32MultiArray>("feedbackGains", 1);

  Inbox inbox;
  // From chassisState, for the operator page (the models read the pose).
  std::atomic<double> applied_steer{0.0}, applied_throttle{0.0};
  std::atomic<bool> chassis_motion{true};
  ros::Subscriber pose_sub = pub_nh.subscribe<nav_msgs::Odometry>(
      pose_topic, 1, [&](const nav_msgs::Odometry::ConstPtr& m) {
        try {
          const OdometryFields f = mppi::ros::fields_of(*m);
          {
            const std::lock_guard<std::mutex> lock(inbox.mutex);
            inbox.pose = f;
            inbox.pose_arrival_s = now_s();
          }
          inbox.wake.notify_one();
        } catch (const std::exception& e) {
          ROS_ERROR_THROTTLE(1.0, "mppi_controller_node: pose callback: %s", e.what());
        }
      }, ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  ros::Subscriber runstop_sub = pub_nh.subscribe<autorally_msgs::runstop>(
      "runstop", 5, [&](const autorally_msgs::runstop::ConstPtr& m) {
        try {
          {
            const std::lock_guard<std::mutex> lock(inbox.mutex);
            // Kept until the loop reads it: a second message may come before the loop wakes.
            inbox.runstop_changed =
                inbox.runstop_changed || !inbox.runstop || inbox.runstop->first != static_cast<bool>(m->motionEnabled);
            inbox.runstop = std::make_pair(static_cast<bool>(m->motionEnabled), now_s());
          }
          inbox.wake.notify_one();
        } catch (const std::exception& e) {
          ROS_ERROR_THROTTLE(1.0, "mppi_controller_node: runstop callback: %s", e.what());
        }
      }, ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  ros::Subscriber state_sub = pub_nh.subscribe<autorally_msgs::chassisState>(
      "chassisState", 1, [&](const autorally_msgs::chassisState::ConstPtr& m) {
        applied_steer = mppi::ros::library_steer_from_chassis(m->steering);
        applied_throttle = m->throttle;
        chassis_motion = static_cast<bool>(m->runstopMotionEnabled);
      });
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  ros::AsyncSpinner spinner(1);
  spinner.start();

  mppi::ros::SafetyMonitor monitor(safety);
  mppi::ros::TimingStats stats;
  const double period_s = 1.0 / s.hz;
  std::vector<float> path_xy;
  autorally_msgs::chassisCommand cmd;
  cmd.sender = sender;
  double last_step_s = -1e9, last_pose_arrival_s = -1.0, next_status_s = 0.0, next_timing_s = 0.0;
  long steps = 0;
  std::optional<OdometryFields> pending;
  bool stopped_sent = false;

  auto publish_command = [&](double steering, double throttle) {
    cmd.steering = mppi::ros::chassis_steering_from_library(steering);
    cmd.throttle = throttle;
    cmd.frontBrake = -5.0;  // as AutoRally's node: the brake is left to another commander
    cmd.header.stamp = ros::Time::now();
    command_pub.publish(cmd);
  };

  while (ros::ok() && !g_stop) {
    bool runstop_changed = false;
    {
      std::unique_lock<std::mutex> lock(inbox.mutex);
      const auto wait = std::chrono::duration<double>(pending ? std::max(0.0, last_step_s + 0.8 * period_s - now_s())
                                                              : period_s);
      inbox.wake.wait_for(lock, wait, [&] { return inbox.pose.has_value() || inbox.runstop_changed || g_stop; });
      if (inbox.pose) {
        pending = inbox.pose;
        if (last_pose_arrival_s >= 0.0) stats.add_pose_interval_s(inbox.pose_arrival_s - last_pose_arrival_s);
        last_pose_arrival_s = inbox.pose_arrival_s;
        monitor.on_pose(inbox.pose_arrival_s);
        inbox.pose.reset();
      }
      if (inbox.runstop) monitor.on_runstop(inbox.runstop->first, inbox.runstop->second);
      runstop_changed = inbox.runstop_changed;
      inbox.runstop_changed = false;
    }
    if (!ros::ok() || g_stop) break;
    try {
      const double t = now_s();
      monitor.on_operator_page(controller->page_motion_allowed());
      mppi::ros::NodeStatus status = monitor.status(t);
      if (!monitor.may_step(t)) {
        // Every period (and at once on a runstop): the safe stop. The plan is kept warm.
        if (runstop_changed || !stopped_sent || t - last_step_s >= period_s * 0.999) {
          publish_command(0.0, 0.0);
          stats.count_safe_stop();
          last_step_s = t;
          stopped_sent = true;
        }
        pending.reset();
      } else if (pending && t - last_step_s >= 0.8 * period_s) {
        stopped_sent = false;
        mppi::VehicleState state;
        const char* why = "";
        if (!mppi::ros::state_from_odometry(*pending, &state, &why)) {
          monitor.on_step(false, std::string("bad pose: ") + why);
          publish_command(0.0, 0.0);
          stats.count_error();
        } else {
          const mppi::ros::NodeController::Step step = controller->step(
              state, t, mppi::Control{static_cast<float>(applied_steer.load()), static_cast<float>(applied_throttle.load())},
              chassis_motion.load());
          monitor.on_step(step.ok, step.reason);
          if (step.ok) {
            publish_command(step.output.steer, step.output.throttle);
            stats.add_latency_ms((ros::Time::now().toSec() - pending->stamp_s) * 1e3);
          } else {
            publish_command(0.0, 0.0);
            stats.count_error();
          }
          stats.add_optimizer_ms(step.optimizer_ms);
          ++steps;
          // The plan's path (from the measured state) and the feedback gains, after the command.
          if (path_every > 0 && steps % path_every == 0 && path_pub.getNumSubscribers() > 0) {
            controller->planned_path(&path_xy);
            path_pub.publish(mppi::ros::path_msg(path_xy, period_s, ros::Time::now(), "map"));
          }
          if (gains_pub && !controller->feedback_gains().empty()) {
            gains_pub.publish(mppi::ros::gains_msg(controller->feedback_gains(), controller->horizon(),
                                                   controller->controls(), controller->model_states()));
          }
        }
        last_step_s = t;
        pending.reset();
        status = monitor.status(now_s());
      }
      if (t >= next_status_s || runstop_changed) {
        autorally_msgs::pathIntegralStatus m;
        m.header.stamp = ros::Time::now();
        m.status = static_cast<int>(status.level);
        m.info = status.info;
        status_pub.publish(m);
        next_status_s = t + 0.1;
      }
      if (t >= next_timing_s) {
        autorally_msgs::pathIntegralTiming m;
        m.header.stamp = ros::Time::now();
        m.averageTimeBetweenPoses = stats.recent_pose_interval_s();
        m.averageOptimizationCycleTime = stats.recent_optimizer_s();
        m.averageSleepTime = std::max(0.0, period_s - m.averageOptimizationCycleTime);
        timing_pub.publish(m);
        next_timing_s = t + 1.0;
      }
    } catch (const std::exception& e) {
      monitor.on_step(false, e.what());
      stats.count_error();
      ROS_ERROR_THROTTLE(1.0, "mppi_controller_node: %s", e.what());
      try {
        publish_command(0.0, 0.0);
      } catch (...) {
      }
    }
  }
  spinner.stop();
  ros::shutdown();
  std::fprintf(stderr, "mppi_controller_node: %zu commands, latency p50 %.2f ms, p99 %.2f ms; optimizer p50 %.2f ms\n",
               stats.commands(), stats.latency_ms_percentile(50), stats.latency_ms_percentile(99),
               stats.optimizer_ms_percentile(50));
  if (!stats_file.empty()) {
    try {
      stats.write_json(stats_file);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mppi_controller_node: %s\n", e.what());
      return 1;
    }
  }
  return 0;
}
