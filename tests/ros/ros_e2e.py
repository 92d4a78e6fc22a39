#!/usr/bin/env python3
"""The ROS nodes end to end, on a private roscore (a free port on 127.0.0.1).

    ros_e2e.py laps   --bin BUILD/ros/bin --sim-bin BUILD/bin
                                        mppi_sim_node + mppi_controller_node drive 3 laps of the
                                        Gazebo oval; checks 0 crashes, the mean lap time within
                                        5 % of mppi-sim's at the same settings (run here), and the
                                        node's odometry-to-command latency p99 <= 20 ms at 50 Hz
    ros_e2e.py safety --bin BUILD/ros/bin --probe-bin BUILD/bin
                                        mppi-ros-safety-probe against mppi_controller_node: a
                                        runstop and a stale pose stop the car within one period

    ros_e2e.py launch --bin BUILD/ros/bin   ros/launch/closed_loop.launch by roslaunch (the nodes as
                                        package mppi_ros), one lap with the tube variant: the lap
                                        without a crash, the feedback gains it publishes, and the
                                        operator page's runstop (when the page is built) in the
                                        node's pathIntegralStatus

Prints the figures and PASS, or FAIL with the reason (exit 1). Python 3 standard library only.
"""
import argparse
import json
import os
import re
import urllib.error
import urllib.request
import signal
import socket
import subprocess
import sys
import tempfile
import time
import xmlrpc.client

# The closed-loop settings: a modest K and T, as the simulator's own closed-loop tests use.
SPEED_MPS = 6.0
SAMPLES = 384
HORIZON = 60
SEED = 3
LAPS = 3
HZ = 50.0


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class RosMaster:
    """roscore on a free port, with its logs in a scratch folder; stopped on exit."""

    def __init__(self, scratch):
        self.port = free_port()
        self.env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % self.port, ROS_IP='127.0.0.1',
                        ROS_HOME=scratch, ROS_LOG_DIR=os.path.join(scratch, 'log'))
        self.env.pop('ROS_HOSTNAME', None)
        self.proc = None
        self.log = open(os.path.join(scratch, 'roscore.log'), 'w')

    def __enter__(self):
        self.proc = subprocess.Popen(['roscore', '-p', str(self.port)], env=self.env, stdout=self.log,
                                     stderr=subprocess.STDOUT, start_new_session=True)
        master = xmlrpc.client.ServerProxy(self.env['ROS_MASTER_URI'])
        deadline = time.time() + 20
        while time.time() < deadline:
            try:
                master.getSystemState('/ros_e2e')
                return self
            except OSError:
                if self.proc.poll() is not None:
                    break
                time.sleep(0.2)
        raise RuntimeError('roscore did not start on port %d (see roscore.log)' % self.port)

    def __exit__(self, *exc):
        stop(self.proc, 10)
        self.log.close()


def stop(proc, timeout_s):
    """SIGINT to the process group, then SIGKILL if it lingers."""
    if proc is None or proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout_s)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    except ProcessLookupError:
        pass


def start(cmd, env, log_path):
    return subprocess.Popen(cmd, env=env, stdout=open(log_path, 'w'), stderr=subprocess.STDOUT,
                            start_new_session=True)


def controller_cmd(bin_dir, stats_file, extra=()):
    return [os.path.join(bin_dir, 'mppi_controller_node'), '_model:=single-track', '_hz:=%g' % HZ,
            '_num_rollouts:=%d' % SAMPLES, '_num_timesteps:=%d' % HORIZON, '_desired_speed:=%g' % SPEED_MPS,
            '_seed:=%d' % SEED, '_stats_file:=' + stats_file, *extra]


def tail(path, n=15):
    try:
        with open(path) as f:
            return ''.join(f.readlines()[-n:])
    except OSError:
        return ''


def run_laps(bin_dir, sim_bin, scratch):
    # mppi-sim at the same settings (its plant waits for no one: simulated time).
    sim = subprocess.run([os.path.join(sim_bin, 'mppi-sim'), '--track', 'gazebo', '--model', 'single-track',
                          '--plant', 'single-track', '--speed', str(SPEED_MPS), '--laps', str(LAPS), '--samples',
                          str(SAMPLES), '--horizon', str(HORIZON), '--seed', str(SEED), '--json', '--quiet'],
                         capture_output=True, text=True, timeout=120)
    if sim.returncode != 0:
        return 'mppi-sim failed: ' + sim.stderr[-500:]
    reference = json.loads(sim.stdout)
    ref_laps = reference['lap_times_s']
    summary_file = os.path.join(scratch, 'sim_summary.json')
    stats_file = os.path.join(scratch, 'controller_stats.json')
    with RosMaster(scratch) as ros:
        controller = start(controller_cmd(bin_dir, stats_file), ros.env, os.path.join(scratch, 'controller.log'))
        simulator = start([os.path.join(bin_dir, 'mppi_sim_node'), '_laps:=%d' % LAPS, '_rate_hz:=%g' % HZ,
                           '_summary_file:=' + summary_file, '_max_time_s:=90'],
                          ros.env, os.path.join(scratch, 'sim.log'))
        try:
            simulator.wait(timeout=110)
        except subprocess.TimeoutExpired:
            stop(simulator, 5)
        stop(controller, 10)
    if not os.path.exists(summary_file):
        return 'no summary from mppi_sim_node:\n' + tail(os.path.join(scratch, 'sim.log'))
    if not os.path.exists(stats_file):
        return 'no timing from mppi_controller_node:\n' + tail(os.path.join(scratch, 'controller.log'))
    with open(summary_file) as f:
        got = json.load(f)
    with open(stats_file) as f:
        stats = json.load(f)
    ros_laps = got['lap_times_s']
    print('mppi-sim:  laps %s s, crashes %d' % (', '.join('%.2f' % t for t in ref_laps), reference['crashes']))
    print('ROS nodes: laps %s s, crashes %d' % (', '.join('%.2f' % t for t in ros_laps), got['crashes']))
    latency = stats['latency_ms']
    print('controller node: %d commands, odometry-to-command latency p50 %s ms, p99 %s ms, max %s ms; '
          'optimizer p50 %s ms' % (stats['commands'], latency['p50'], latency['p99'], latency['max'],
                                    stats['optimizer_ms']['p50']))
    failures = []
    if got['laps'] < LAPS:
        failures.append('the ROS loop drove %d of %d laps' % (got['laps'], LAPS))
    if got['crashes'] != 0:
        failures.append('%d crashes: %s' % (got['crashes'], '; '.join(got['crash_reasons'])))
    if len(ref_laps) < LAPS:
        failures.append('mppi-sim drove %d of %d laps' % (len(ref_laps), LAPS))
    if ros_laps and ref_laps:
        ratio = (sum(ros_laps) / len(ros_laps)) / (sum(ref_laps) / len(ref_laps))
        print('mean lap time ratio ROS / mppi-sim: %.4f' % ratio)
        if abs(ratio - 1.0) > 0.05:
            failures.append('mean lap time %.1f %% off mppi-sim\'s (limit 5 %%)' % ((ratio - 1.0) * 100))
    p99 = latency['p99']
    if p99 is None or p99 > 20.0:
        failures.append('latency p99 %s ms > 20 ms' % p99)
    return '; '.join(failures)


def run_safety(bin_dir, probe_bin, scratch):
    stats_file = os.path.join(scratch, 'controller_stats.json')
    with RosMaster(scratch) as ros:
        controller = start(controller_cmd(bin_dir, stats_file), ros.env, os.path.join(scratch, 'controller.log'))
        try:
            probe = subprocess.run([os.path.join(probe_bin, 'mppi-ros-safety-probe'), '_hz:=%g' % HZ], env=ros.env,
                                   capture_output=True, text=True, timeout=60)
        finally:
            stop(controller, 10)
    print(probe.stdout, end='')
    if probe.returncode != 0 or 'PASS' not in probe.stdout:
        return 'the safety probe failed (exit %d): %s\n%s' % (probe.returncode, probe.stderr[-500:],
                                                              tail(os.path.join(scratch, 'controller.log')))
    return ''


def run_launch(bin_dir, scratch):
    launch = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'ros', 'launch', 'closed_loop.launch')
    summary_file = os.path.join(scratch, 'sim_summary.json')
    stats_file = os.path.join(scratch, 'controller_stats.json')
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % port, ROS_IP='127.0.0.1', ROS_HOME=scratch,
               ROS_LOG_DIR=os.path.join(scratch, 'log'),
               ROS_PACKAGE_PATH=os.path.dirname(os.path.abspath(bin_dir)),
               # the generated autorally_msgs classes, for rostopic
               PYTHONPATH=os.pathsep.join(p for p in [os.path.join(os.path.dirname(os.path.abspath(bin_dir)), 'python'),
                                                      os.environ.get('PYTHONPATH', '')] if p))
    env.pop('ROS_HOSTNAME', None)
    page_port = free_port()
    log_path = os.path.join(scratch, 'roslaunch.log')
    proc = start(['roslaunch', '-p', str(port), launch, 'laps:=1', 'variant:=tube', 'num_rollouts:=%d' % SAMPLES,
                  'num_timesteps:=%d' % HORIZON, 'desired_speed:=%g' % SPEED_MPS, 'summary_file:=' + summary_file,
                  'stats_file:=' + stats_file, 'serve_port:=%d' % page_port], env, log_path)
    gains = None
    page_runstop = None  # None: no page in this build; else what the node's status said
    try:
        # The feedback gains, read off the topic while the car drives.
        deadline = time.time() + 20
        while time.time() < deadline and gains is None and proc.poll() is None:
            echo = subprocess.run(['rostopic', 'echo', '-n', '1', '/feedbackGains/layout'], env=env,
                                  capture_output=True, text=True, timeout=15)
            if echo.returncode == 0 and 'label' in echo.stdout:
                gains = echo.stdout
        # The operator page's RUNSTOP: the node's status says so, then released.
        with open(log_path) as f:
            token = re.search(r'127\.0\.0\.1:%d/\?token=([0-9a-f]+)' % page_port, f.read())
        if token:
            def control(query):
                req = urllib.request.Request('http://127.0.0.1:%d/api/control?%s' % (page_port, query), data=b'',
                                            method='POST', headers={'X-MPPI-Token': token.group(1)})
                with urllib.request.urlopen(req, timeout=5) as r:
                    return r.status
            page_runstop = 'POST runstop=1 answered %s' % control('runstop=1')
            for _ in range(5):
                status = subprocess.run(['rostopic', 'echo', '-n', '1', '/pathIntegralStatus/info'], env=env,
                                        capture_output=True, text=True, timeout=15).stdout
                if 'operator page' in status:
                    page_runstop = 'status: ' + status.split('\n')[0]
                    break
            control('runstop=0')
        proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        pass
    finally:
        stop(proc, 10)
    if not os.path.exists(summary_file):
        return 'no summary from the launched mppi_sim_node:\n' + tail(os.path.join(scratch, 'roslaunch.log'))
    with open(summary_file) as f:
        got = json.load(f)
    print('roslaunch closed_loop.launch (tube): laps %s s, crashes %d' %
          (', '.join('%.2f' % t for t in got['lap_times_s']), got['crashes']))
    failures = []
    if got['laps'] != 1 or got['crashes'] != 0:
        failures.append('%d laps, %d crashes (want 1 lap, no crash)' % (got['laps'], got['crashes']))
    if gains is None:
        failures.append('no feedbackGains from the tube controller')
    else:
        sizes = [int(line.split(':')[1]) for line in gains.splitlines() if line.strip().startswith('size:')]
        print('feedbackGains layout sizes (t, control, state): %s' % sizes)
        if sizes[:2] != [HORIZON, 2] or len(sizes) < 3 or sizes[2] < 7:
            failures.append('feedbackGains layout %s, want [%d, 2, nx >= 7]' % (sizes, HORIZON))
    if page_runstop is not None:
        print('operator page runstop -> %s' % page_runstop)
        if 'operator page' not in page_runstop:
            failures.append('the operator page\'s runstop did not reach the node\'s status (%s)' % page_runstop)
    return '; '.join(failures)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('mode', choices=['laps', 'safety', 'launch'])
    ap.add_argument('--bin', required=True, help='folder of mppi_sim_node and mppi_controller_node')
    ap.add_argument('--sim-bin', help='folder of mppi-sim (laps; default: --bin)')
    ap.add_argument('--probe-bin', help='folder of mppi-ros-safety-probe (safety; default: --bin)')
    ap.add_argument('--keep', help='keep the logs in this folder')
    args = ap.parse_args()
    scratch = args.keep or tempfile.mkdtemp(prefix='mppi_ros_e2e_')
    os.makedirs(scratch, exist_ok=True)
    try:
        if args.mode == 'laps':
            why = run_laps(args.bin, args.sim_bin or args.bin, scratch)
        elif args.mode == 'safety':
            why = run_safety(args.bin, args.probe_bin or args.bin, scratch)
        else:
            why = run_launch(args.bin, scratch)
    except Exception as e:  # a test harness: any failure is reported, never a traceback alone
        why = '%s: %s' % (type(e).__name__, e)
    if why:
        print('FAIL: ' + why)
        print('logs in ' + scratch)
        return 1
    print('PASS')
    return 0


if __name__ == '__main__':
    sys.exit(main())
