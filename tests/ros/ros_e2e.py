#!/usr/bin/env python3
"""The ROS nodes end to end, on a private roscore (a free port on 127.0.0.1).

    ros_e2e.py laps   --bin BUILD/ros/bin --sim-bin BUILD/bin
                                        mppi_sim_node + mppi_controller_node drive 3 laps of the
                                        Gazebo oval; checks 0 crashes, the median lap time within
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

    ros_e2e.py record --bin BUILD/ros/bin --fit-bin BUILD/bin
                                        the loop (one lap) recorded by `rosbag record`, read back by
                                        `mppi-fit convert`: the bag's drive against the simulator's
                                        own summary (lap time, the lap closed, 50 Hz without gaps,
                                        the twist against the positions, the steering's sign)
    ros_e2e.py diagnose --bin BUILD/ros/bin --fit-bin BUILD/bin
                                        two 30-s drives recorded by `rosbag record` and diagnosed by
                                        `mppi-fit diagnose --log x.bag` against the simulator's own
                                        plant: matched, no effect named; with steering_delay_s 0.08,
                                        the steering delay named (or in the partial correction beside
                                        an unexplained mismatch), its estimate in [0.05, 0.12] s
                                        (--stability-resamples N: the diagnosis' stability selection)

Prints the figures and PASS, or FAIL with the reason (exit 1). Python 3 standard library only.
"""
import argparse
import json
import math
import os
import re
import urllib.error
import urllib.request
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import xmlrpc.client

SOURCE_DIR = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))

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
        # The median lap: the ROS loop runs in wall-clock time, so one lap driven while another
        # process held both cores (a compile beside the suite) does not decide alone.
        ratio = statistics.median(ros_laps) / statistics.median(ref_laps)
        print('median lap time ratio ROS / mppi-sim: %.4f' % ratio)
        if abs(ratio - 1.0) > 0.05:
            failures.append('median lap time %.1f %% off mppi-sim\'s (limit 5 %%)' % ((ratio - 1.0) * 100))
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
            # The runstop is held only until the status says so: a safe stop coasts with the wheels
            # straight, and a long one in a corner leaves the road whatever the controller does.
            echo_log = os.path.join(scratch, 'status_echo.log')
            watcher = start(['rostopic', 'echo', '/pathIntegralStatus/info'], dict(env, PYTHONUNBUFFERED='1'), echo_log)
            try:
                connect_deadline = time.time() + 15  # the subscriber hears a status (one per 0.1 s)
                while time.time() < connect_deadline and os.path.getsize(echo_log) == 0:
                    time.sleep(0.05)
                page_runstop = 'POST runstop=1 answered %s' % control('runstop=1')
                runstop_deadline = time.time() + 10
                while time.time() < runstop_deadline and 'operator page' not in page_runstop:
                    time.sleep(0.05)
                    with open(echo_log) as f:
                        said = [line for line in f if 'operator page' in line]
                    if said:
                        page_runstop = 'status: ' + said[0].strip()
                control('runstop=0')
            finally:
                stop(watcher, 5)
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
        failures.append('%d laps, %d crashes (want 1 lap, no crash): %s' %
                        (got['laps'], got['crashes'], '; '.join(got.get('crash_reasons', []))))
    if os.path.exists(stats_file):
        with open(stats_file) as f:
            stats = json.load(f)
        print('controller: %d commands, optimizer p50 %s ms, p99 %s ms, %d safe stops' %
              (stats['commands'], stats['optimizer_ms']['p50'], stats['optimizer_ms']['p99'], stats['safe_stops']))
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


# ---- rosbag record -> mppi-fit ----------------------------------------------------------------
# AutoRally's topics as its own bags hold them (docs/ROSBAG.md); the loop publishes no wheel speeds.
BAG_TOPICS = ['/pose_estimate', '/chassisState', '/chassisCommand']
# How mppi-fit reads these bags. The nodes carry the library's steering sign (+1 turns left) in
# chassisCommand / chassisState; the simulator's chassisState reports the actuators' positions
# (after the steering delay and the rate limits), so the controls are the controller's commands;
# and the controller answers each pose within a few ms, its command stamped when sent, so the
# answer to pose k is row k's (command_lead_s: half a row; without it every command is read one
# row late and the diagnosis sees a time offset of about -0.02 s).
BAG_READING = ['--topic', 'controls=command,command_lead_s=0.01']
# The simulator's plant as the diagnosis' nominal: mppi_sim_node's single-track parameters, and its
# actuators acting at once (the nominal models have no rate limits; sim::ActuatorLimits' default
# 5 /s would be a steer_rate_limit the diagnosis names, rightly).
PLANT_PARAMS = os.path.join(SOURCE_DIR, 'data', 'config', 'autorally_single_track.yaml')
FAST_ACTUATORS = ['_steering_rate_per_s:=10000', '_throttle_rate_per_s:=10000']


def wait_for_subscriber(env, topic, node_prefix, timeout_s=20):
    master = xmlrpc.client.ServerProxy(env['ROS_MASTER_URI'])
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        _, _, (_, subscribers, _) = master.getSystemState('/ros_e2e')
        for name, nodes in subscribers:
            if name == topic and any(n.startswith(node_prefix) for n in nodes):
                return True
        time.sleep(0.2)
    return False


def record_drive(bin_dir, scratch, name, sim_params, sim_timeout_s):
    """The loop on its own roscore, recorded by `rosbag record`; returns (bag, summary) or raises."""
    bag = os.path.join(scratch, name + '.bag')
    summary_file = os.path.join(scratch, name + '_summary.json')
    stats_file = os.path.join(scratch, name + '_controller_stats.json')
    with RosMaster(scratch) as ros:
        recorder = start(['rosbag', 'record', '--tcpnodelay', '-O', bag, *BAG_TOPICS], ros.env,
                         os.path.join(scratch, name + '_rosbag.log'))
        controller = simulator = None
        try:
            # rosbag record subscribes before anything is published, so the bag holds the whole drive
            if not wait_for_subscriber(ros.env, '/chassisCommand', '/record'):
                raise RuntimeError('rosbag record did not subscribe:\n' + tail(os.path.join(scratch, name + '_rosbag.log')))
            controller = start(controller_cmd(bin_dir, stats_file), ros.env, os.path.join(scratch, name + '_controller.log'))
            simulator = start([os.path.join(bin_dir, 'mppi_sim_node'), '_rate_hz:=%g' % HZ,
                               '_summary_file:=' + summary_file, *sim_params],
                              ros.env, os.path.join(scratch, name + '_sim.log'))
            try:
                simulator.wait(timeout=sim_timeout_s)
            except subprocess.TimeoutExpired:
                stop(simulator, 5)
        finally:
            # SIGINT: rosbag record closes and indexes the bag (x.bag.active -> x.bag)
            stop(recorder, 20)
            stop(controller, 10)
            stop(simulator, 5)
    if not os.path.exists(summary_file):
        raise RuntimeError('no summary from mppi_sim_node:\n' + tail(os.path.join(scratch, name + '_sim.log')))
    if not os.path.exists(bag):
        raise RuntimeError('rosbag record left no closed bag:\n' + tail(os.path.join(scratch, name + '_rosbag.log')))
    with open(summary_file) as f:
        return bag, json.load(f)


def read_recording(path):
    """A recording CSV (docs/RECORDING_FORMAT.md) -> {column: [float or None]}."""
    with open(path) as f:
        lines = [line.rstrip('\n') for line in f if not line.startswith('#')]
    header = lines[0].split(',')
    cols = {h: [] for h in header}
    for line in lines[1:]:
        for h, v in zip(header, line.split(',')):
            cols[h].append(float(v) if v != '' else None)
    return cols


def run_record(bin_dir, fit_bin, scratch):
    t_start = time.time()
    bag, summary = record_drive(bin_dir, scratch, 'lap', ['_laps:=1', '_max_time_s:=40'], 60)
    t_drive = time.time() - t_start
    csv = os.path.join(scratch, 'lap.csv')
    conv = subprocess.run([os.path.join(fit_bin, 'mppi-fit'), 'convert', bag, '--out', csv, *BAG_READING],
                          capture_output=True, text=True, timeout=60)
    if conv.returncode != 0:
        return 'mppi-fit convert failed: ' + conv.stderr[-800:]
    print(conv.stdout.strip())
    info = subprocess.run(['rosbag', 'info', bag], capture_output=True, text=True, timeout=60, env=os.environ)
    print('\n'.join(line for line in info.stdout.splitlines() if 'msgs' in line or 'duration' in line))
    r = read_recording(csv)
    t, x, y, vx, vy = r['t'], r['x'], r['y'], r['vx'], r['vy']
    n = len(t)
    failures = []
    if summary['laps'] != 1 or summary['crashes'] != 0:
        failures.append('the simulator drove %d laps with %d crashes (want 1, 0)' % (summary['laps'], summary['crashes']))
    if n < 100:
        return 'the bag gave %d rows' % n
    dt = (t[-1] - t[0]) / (n - 1)
    missing = sum(1 for i in range(n) if x[i] is None or vx[i] is None)
    speed = [math.hypot(vx[i], vy[i]) if vx[i] is not None else 0.0 for i in range(n)]
    moving = [i for i in range(n) if speed[i] > 0.05]
    drive_s = t[moving[-1]] - t[moving[0]] + dt if moving else 0.0
    lap_s = summary['lap_times_s'][0] if summary['lap_times_s'] else float('nan')
    first, last = moving[0] if moving else 0, n - 1
    gap_m = math.hypot(x[last] - x[first], y[last] - y[first])
    # the twist (world frame in the bag, body frame in the CSV) against the positions' derivative
    dv = [abs(math.hypot(x[i + 1] - x[i - 1], y[i + 1] - y[i - 1]) / (t[i + 1] - t[i - 1]) - speed[i])
          for i in range(1, n - 1) if None not in (x[i - 1], x[i + 1])]
    dv_mean = sum(dv) / len(dv)
    # the controls: present while the car drives, and steering left turns left
    ctl = [i for i in moving if r['steer'][i] is not None and r['throttle'][i] is not None]
    # (the yaw rate follows the steering's recent mean: MPPI's commands are noisy row to row)
    steer = [v if v is not None else 0.0 for v in r['steer']]
    smooth = [sum(steer[max(0, i - 24):i + 1]) / len(steer[max(0, i - 24):i + 1]) for i in range(n)]
    pairs = [(smooth[i], r['yaw_rate'][i]) for i in ctl if r['yaw_rate'][i] is not None]
    ms = sum(p[0] for p in pairs) / len(pairs)
    mw = sum(p[1] for p in pairs) / len(pairs)
    cov = sum((a - ms) * (b - mw) for a, b in pairs)
    corr = cov / math.sqrt(sum((a - ms) ** 2 for a, _ in pairs) * sum((b - mw) ** 2 for _, b in pairs))
    print('simulator: 1 lap %.2f s, %d crashes; the bag: %d rows at %.1f Hz, %d without a pose, driving %.2f s, '
          'lap closed within %.2f m, |speed from positions - twist| mean %.3f m/s, controls on %d of %d driving rows, '
          'corr(the steering\'s 0.5-s mean, yaw rate) %.2f; drive with recording %.1f s' %
          (lap_s, summary['crashes'], n, 1.0 / dt, missing, drive_s, gap_m, dv_mean, len(ctl), len(moving), corr, t_drive))
    if abs(1.0 / dt - HZ) > 0.5:
        failures.append('rows at %.2f Hz, want %g' % (1.0 / dt, HZ))
    if missing:
        failures.append('%d rows without a pose' % missing)
    if not abs(drive_s - lap_s) <= 0.3:
        failures.append('the bag drives %.2f s, the simulator timed its lap %.2f s (tolerance 0.3 s)' % (drive_s, lap_s))
    if gap_m > 2.0:
        failures.append('the lap does not close in the bag: %.2f m from its start' % gap_m)
    if dv_mean > 0.1:
        failures.append('the twist differs from the positions by %.3f m/s on average' % dv_mean)
    if len(ctl) < 0.95 * len(moving):
        failures.append('controls on %d of %d driving rows' % (len(ctl), len(moving)))
    if corr < 0.25:
        failures.append('the steering\'s 0.5-s mean and the yaw rate correlate %.2f (a steering sign or timing fault)' % corr)
    return '; '.join(failures)


DRIVE_S = 30.0
DELAY_S = 0.08


def diagnose_bag(fit_bin, bag, out, resamples):
    t0 = time.time()
    d = subprocess.run([os.path.join(fit_bin, 'mppi-fit'), 'diagnose', '--log', bag, '--model', 'single-track',
                        '--params', PLANT_PARAMS, *BAG_READING, '--no-plots', '--quiet',
                        '--stability-resamples', str(resamples), '--max-effects', '2', '--out', out],
                       capture_output=True, text=True, timeout=600)
    if d.returncode != 0:
        raise RuntimeError('mppi-fit diagnose %s failed (exit %d): %s' % (bag, d.returncode, d.stderr[-800:]))
    with open(os.path.join(out, 'report.json')) as f:
        return json.load(f), time.time() - t0


def run_diagnose(bin_dir, fit_bin, scratch, resamples):
    failures = []
    for name, delay in (('matched', 0.0), ('delayed', DELAY_S)):
        t0 = time.time()
        bag, summary = record_drive(bin_dir, scratch, name,
                                    ['_max_time_s:=%g' % DRIVE_S, '_steering_delay_s:=%g' % delay, *FAST_ACTUATORS],
                                    DRIVE_S + 40)
        t_drive = time.time() - t0
        report, t_diag = diagnose_bag(fit_bin, bag, os.path.join(scratch, name + '_diagnosis'), resamples)
        selected = report['selected']
        # Beside an unexplained mismatch the chosen effects are a partial correction, not names: a
        # term the data do not hold (the fast selection here has no stability resamples) leaves one.
        partial = report.get('partial', [])
        params = report['final_params']
        rmse = report['heldout_1s_normalized_rmse']
        print('%s (steering_delay_s %g): %.0f s simulated, %d laps, %d crashes, %d rows; named %s, partial %s %s; '
              'suspected %s; verdict: %s; held-out 1-s normalised RMSE %.4f -> %.4f; drive %.1f s, diagnose %.1f s' %
              (name, delay, summary['sim_time_s'], summary['laps'], summary['crashes'], report['rows'],
               selected or 'nothing', partial or 'nothing',
               {k: round(v['value'], 4) for k, v in params.items()} if params else '',
               [s['id'] for s in report['suspected']] or 'nothing', report['verdict'], rmse['nominal'],
               rmse['corrected'], t_drive, t_diag))
        if summary['crashes']:
            failures.append('%s: %d crashes' % (name, summary['crashes']))
        if delay == 0.0:
            if selected or partial:
                failures.append('matched: named %s, partial %s' % (selected, partial))
        else:
            # the steering's delay family; where both forms are named, the mean delay of the chain
            # (a pure delay d, then a first-order lag tau) is d + tau
            family = {'steer_delay': 'steer_delay_s', 'steer_lag': 'steer_lag_s'}
            found = [(e, params[family[e]]['value']) for e in selected + partial if e in family and family[e] in params]
            total = sum(v for _, v in found)
            print('delayed: the steering\'s delay estimate %.4f s (%s), true %g s' %
                  (total, ' + '.join('%s %.4f' % f for f in found) or 'none named', DELAY_S))
            if not found:
                failures.append('delayed: no steering delay named (named %s)' % (selected or 'nothing'))
            elif not 0.05 <= total <= 0.12:
                failures.append('delayed: steering delay estimate %.4f s, outside [0.05, 0.12]' % total)
    return '; '.join(failures)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('mode', choices=['laps', 'safety', 'launch', 'record', 'diagnose'])
    ap.add_argument('--bin', required=True, help='folder of mppi_sim_node and mppi_controller_node')
    ap.add_argument('--sim-bin', help='folder of mppi-sim (laps; default: --bin)')
    ap.add_argument('--probe-bin', help='folder of mppi-ros-safety-probe (safety; default: --bin)')
    ap.add_argument('--fit-bin', help='folder of mppi-fit (record, diagnose; default: --bin)')
    ap.add_argument('--stability-resamples', type=int, default=0,
                    help='diagnose: mppi-fit diagnose\'s stability resamples (0: off, as rosbag.end_to_end)')
    ap.add_argument('--keep', help='keep the logs in this folder')
    args = ap.parse_args()
    scratch = args.keep or tempfile.mkdtemp(prefix='mppi_ros_e2e_')
    os.makedirs(scratch, exist_ok=True)
    try:
        if args.mode == 'laps':
            why = run_laps(args.bin, args.sim_bin or args.bin, scratch)
        elif args.mode == 'safety':
            why = run_safety(args.bin, args.probe_bin or args.bin, scratch)
        elif args.mode == 'record':
            why = run_record(args.bin, args.fit_bin or args.bin, scratch)
        elif args.mode == 'diagnose':
            why = run_diagnose(args.bin, args.fit_bin or args.bin, scratch, args.stability_resamples)
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
