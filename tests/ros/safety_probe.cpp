// mppi-ros-safety-probe: drives a running mppi_controller_node as its plant (the simulated car,
// fed with the node's commands) and checks its safety stops. 1) with motion allowed the node
// drives (throttle > 0); 2) a runstop (motionEnabled false) brings the stop command (steering 0,
// throttle 0) within one control period, and every later command is a stop; 3) motion allowed
// again, it drives again; 4) when the poses stop, the stop command comes within one control
// period of the pose turning stale (~pose_timeout_s, default 0.5 s) and every later command is a
// stop. Prints each measured delay and PASS, or FAIL with the reason (exit 1).
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <autorally_msgs/chassisCommand.h>
#include <autorally_msgs/runstop.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include "ros/chassis_convention.hpp"
#include "ros/nodes/ros_messages.hpp"
#include "ros/sim_car.hpp"

namespace {

struct Received {
  double stamp_s, arrival_s, steering, throttle;
  bool is_stop() const { return steering == 0.0 && throttle == 0.0; }
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "mppi_safety_probe");
  ros::NodeHandle nh("~"), pub_nh;
  double hz = 50.0, pose_timeout_s = 0.5, tolerance_s = 0.002;
  nh.param("hz", hz, hz);
  nh.param("pose_timeout_s", pose_timeout_s, pose_timeout_s);
  nh.param("tolerance_s", tolerance_s, tolerance_s);  // transport allowance beyond the period
  const double period_s = 1.0 / hz;

  std::mutex mutex;
  std::vector<Received> received;
  mppi::ros::SimCar car(mppi::ros::SimCarSettings{});
  ros::Publisher pose_pub = pub_nh.advertise<nav_msgs::Odometry>("/pose_estimate", 1);
  ros::Publisher runstop_pub = pub_nh.advertise<autorally_msgs::runstop>("runstop", 1);
  ros::Subscriber sub = pub_nh.subscribe<autorally_msgs::chassisCommand>(
      "chassisCommand", 50, [&](const autorally_msgs::chassisCommand::ConstPtr& m) {
        const std::lock_guard<std::mutex> lock(mutex);
        received.push_back({m->header.stamp.toSec(), ros::Time::now().toSec(), m->steering, m->throttle});
      }, ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  ros::AsyncSpinner spinner(1);
  spinner.start();

  // Wait for the node.
  const double give_up = ros::Time::now().toSec() + 20.0;
  while (ros::ok() && (sub.getNumPublishers() == 0 || pose_pub.getNumSubscribers() == 0 ||
                       runstop_pub.getNumSubscribers() == 0)) {
    if (ros::Time::now().toSec() > give_up) {
      std::printf("FAIL: no mppi_controller_node within 20 s\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }

  bool motion = true, poses = true;
  double t0 = ros::Time::now().toSec();
  std::size_t used = 0;
  // Runs the plant in real time for `duration_s`: poses at hz, runstop at 10 Hz, commands in.
  auto run = [&](double duration_s) {
    const double end = ros::Time::now().toSec() + duration_s;
    ros::Rate rate(hz);
    int n = 0;
    while (ros::ok() && ros::Time::now().toSec() < end) {
      const double t = ros::Time::now().toSec() - t0;
      {
        const std::lock_guard<std::mutex> lock(mutex);
        for (; used < received.size(); ++used)
          car.command({static_cast<float>(mppi::ros::library_steer_from_chassis(received[used].steering)), static_cast<float>(received[used].throttle)},
                      car.time_s());
      }
      car.advance_to(t);
      if (poses) {
        pose_pub.publish(mppi::ros::odometry_msg(car.state(), ros::Time::now(), "map"));
      }
      if (n++ % 5 == 0) {
        autorally_msgs::runstop r;
        r.header.stamp = ros::Time::now();
        r.sender = "probe";
        r.motionEnabled = motion;
        runstop_pub.publish(r);
      }
      rate.sleep();
    }
  };
  auto commands_since = [&](double t_s) {
    const std::lock_guard<std::mutex> lock(mutex);
    std::vector<Received> out;
    for (const Received& r : received)
      if (r.stamp_s >= t_s) out.push_back(r);
    return out;
  };
  // The first stop at or after `from`, and whether every command stamped after from + period is a stop.
  auto check_stop = [&](double from, const char* what, double* delay_s) {
    const std::vector<Received> after = commands_since(from);
    double first = -1.0;
    for (const Received& r : after)
      if (r.is_stop()) {
        first = r.stamp_s;
        break;
      }
    if (first < 0.0) {
      std::printf("FAIL: no stop command after the %s\n", what);
      return false;
    }
    *delay_s = first - from;
    for (const Received& r : after)
      if (r.stamp_s > from + period_s + tolerance_s && !r.is_stop()) {
        std::printf("FAIL: a driving command %.3f s after the %s (steering %.3f, throttle %.3f)\n", r.stamp_s - from,
                    what, r.steering, r.throttle);
        return false;
      }
    return true;
  };
  auto drives_since = [&](double t_s) {
    for (const Received& r : commands_since(t_s))
      if (r.throttle > 0.05) return true;
    return false;
  };

  bool ok = true;
  run(2.0);
  if (!drives_since(t0)) {
    std::printf("FAIL: the node did not drive with motion allowed (%zu commands)\n", received.size());
    ok = false;
  }
  // Runstop.
  motion = false;
  const double runstop_at = ros::Time::now().toSec();
  {
    autorally_msgs::runstop r;
    r.header.stamp = ros::Time::now();
    r.sender = "probe";
    r.motionEnabled = false;
    runstop_pub.publish(r);
  }
  run(1.0);
  double runstop_delay_s = NAN;
  ok = check_stop(runstop_at, "runstop", &runstop_delay_s) && ok;
  // Motion again.
  motion = true;
  const double resume_at = ros::Time::now().toSec();
  run(1.5);
  if (!drives_since(resume_at)) {
    std::printf("FAIL: the node did not drive again after the runstop was released\n");
    ok = false;
  }
  // Stale pose.
  poses = false;
  const double last_pose_at = ros::Time::now().toSec();
  run(pose_timeout_s + 0.5);
  double stale_delay_s = NAN;
  ok = check_stop(last_pose_at + pose_timeout_s, "pose turning stale", &stale_delay_s) && ok;
  std::printf("control period %.1f ms; runstop -> stop command %.1f ms; pose stale (%.2f s) -> stop command %.1f ms\n",
              period_s * 1e3, runstop_delay_s * 1e3, pose_timeout_s, stale_delay_s * 1e3);
  if (ok && !(runstop_delay_s <= period_s + tolerance_s)) {
    std::printf("FAIL: the runstop took longer than one control period\n");
    ok = false;
  }
  if (ok && !(stale_delay_s <= period_s + tolerance_s)) {
    std::printf("FAIL: the stale pose took longer than one control period\n");
    ok = false;
  }
  spinner.stop();
  std::printf(ok ? "PASS\n" : "FAIL\n");
  return ok ? 0 : 1;
}
