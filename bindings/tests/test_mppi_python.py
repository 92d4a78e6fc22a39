"""pytest for the `mppi` Python module (run by ctest as python.pytest, PYTHONPATH = build/python).

The oracle for the closed loop is the C++ program: `mppi-sim` (path in $MPPI_SIM_EXE) run with
the same settings and seed must give the same laps, lap times and crashes as
mppi.run_closed_loop through the bindings.
"""
import json
import math
import os
import subprocess

import numpy as np
import pytest

import mppi
from gil_check import run_counting_main_thread

SIM = os.environ.get("MPPI_SIM_EXE", "")
DATA = os.environ.get("MPPI_DATA_DIR") or mppi.data_dir()

# a short, fast run: the single-track controller drives the single-track plant 2 laps without a
# crash (the kinematic bicycle as the controller's model loses the calibrated plant in the turns)
RUN = dict(track="gazebo", model="single-track", plant="single-track", speed=6.0, laps=2,
           samples=512, seed=7)


def sim_config(out_dir=""):
    c = mppi.ClosedLoopConfig()
    c.track, c.model, c.plant = RUN["track"], RUN["model"], RUN["plant"]
    c.target_speed_mps = RUN["speed"]
    c.laps = RUN["laps"]
    c.controller.num_samples = RUN["samples"]
    c.controller.seed = RUN["seed"]
    c.controller.smoothing_window = 5  # mppi-sim's default (upstream's plan smoothing); the library's is off
    c.progress = False
    c.out_dir = out_dir
    return c


@pytest.fixture(scope="module")
def cpp_run(tmp_path_factory):
    if not SIM or not os.path.exists(SIM):
        pytest.skip("MPPI_SIM_EXE not set (run through ctest)")
    out = tmp_path_factory.mktemp("cpp")
    cmd = [SIM, "--track", RUN["track"], "--model", RUN["model"], "--plant", RUN["plant"],
           "--speed", str(RUN["speed"]), "--laps", str(RUN["laps"]), "--samples", str(RUN["samples"]),
           "--seed", str(RUN["seed"]), "--quiet", "--json", "--out", str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=500)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout), out


def test_closed_loop_matches_cpp_program(cpp_run, tmp_path):
    cpp, _ = cpp_run
    py = mppi.run_closed_loop(sim_config(str(tmp_path)))
    assert py.laps_completed == cpp["laps_completed"] == RUN["laps"]
    assert py.finished and cpp["finished"]
    assert py.crashes == cpp["crashes"]
    assert py.crash_reasons == cpp["crash_reasons"]
    assert py.stalls == cpp["stalls"] == 0
    assert py.lap_times_s == cpp["lap_times_s"]  # same seed: the same run, to the last bit
    assert py.sim_time_s == cpp["sim_time_s"]
    assert py.mean_speed_mps == cpp["mean_speed_mps"]
    assert py.max_speed_mps == cpp["max_speed_mps"]
    assert (py.samples, py.seed, py.model) == (RUN["samples"], RUN["seed"], RUN["model"])
    assert json.loads(py.to_json())["lap_times_s"] == cpp["lap_times_s"]


def test_limit_lap_by_collocation_from_python(cpp_run):
    cpp, _ = cpp_run
    assert cpp["limit_lap_method"] == "qss"
    c = sim_config()
    c.laps = 1
    c.limit_lap_method = "collocation"
    py = mppi.run_closed_loop(c)
    assert py.limit_lap_method == "collocation"
    # the car's own equations cannot hold the tyre's peak in every turn as the QSS lap assumes
    assert py.limit_lap_s > cpp["limit_lap_s"] * 1.02
    # lap 1 starts from rest: it is measured against the standing-start limit lap
    assert py.standing_limit_lap_s > py.limit_lap_s
    assert py.lap_time_ratio[0] == pytest.approx(py.lap_times_s[0] / py.standing_limit_lap_s)
    c.limit_lap_method = "fastest"
    with pytest.raises(Exception, match="unknown limit-lap method 'fastest'"):
        mppi.run_closed_loop(c)


def test_read_recording_of_cpp_run(cpp_run, tmp_path):
    cpp, out = cpp_run
    rec = mppi.read_recording(str(out / "log.csv"))
    assert rec["metadata"]["source"] == "mppi-sim"
    assert rec["metadata"]["seed"] == str(RUN["seed"])
    cols = rec["columns"]
    assert rec["column_names"][:9] == ["t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle"]
    t = cols["t"]
    assert t.dtype == np.float64 and np.all(np.diff(t) > 0)
    assert t[-1] == pytest.approx(cpp["sim_time_s"], abs=0.05)
    assert int(np.nanmax(cols["lap"])) == RUN["laps"]
    # the log holds the controller-rate samples of the speeds the summary's maximum was taken from
    speed = np.hypot(cols["vx"], cols["vy"])
    assert cpp["max_speed_mps"] * 0.97 <= np.nanmax(speed) <= cpp["max_speed_mps"] * (1 + 1e-6)


def test_recording_round_trip(tmp_path):
    n = 50
    t = np.arange(n) * 0.02
    cols = {name: np.sin(t * (i + 1)) for i, name in
            enumerate(["x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle"])}
    cols["t"] = t
    cols["extra"] = np.where(np.arange(n) % 7 == 0, np.nan, t * 3)
    path = str(tmp_path / "r.csv")
    mppi.write_recording(path, cols, {"source": "pytest", "note": "round trip"})
    rec = mppi.read_recording(path)
    assert rec["metadata"] == {"source": "pytest", "note": "round trip"}
    assert rec["column_names"][-1] == "extra"
    for name, v in cols.items():
        got = rec["columns"][name]
        assert np.array_equal(np.isnan(got), np.isnan(v)), name
        np.testing.assert_allclose(got[~np.isnan(v)], v[~np.isnan(v)], rtol=1e-12, atol=1e-15)
    with pytest.raises(mppi.Error, match="throttle"):
        mppi.write_recording(str(tmp_path / "bad.csv"), {k: v for k, v in cols.items() if k != "throttle"})
    (tmp_path / "broken.csv").write_text("t,x,y,yaw,vx,vy,yaw_rate,steer,throttle\n0,1,2,3,4,5,6,7\n")
    with pytest.raises(mppi.Error, match="broken.csv:2"):
        mppi.read_recording(str(tmp_path / "broken.csv"))


def peer_options(k=1024):
    o = mppi.ControllerOptions()
    o.num_samples = k
    o.lambda_ = 1.0
    o.gamma = 1.0
    o.noise_std = [0.2, 0.2]
    o.control_min = [-0.35, -0.5]
    o.control_max = [0.5, 0.5]
    o.safe_control = [0.0, 0.0]
    return o


def test_diff_drive_controller_drives_to_the_goal():
    cost = mppi.GoalObstacleCost(mppi.CostMap.square_obstacles())
    o = peer_options()
    o.num_threads = 1  # many short steps: no thread hand-offs on a busy shared machine
    c = mppi.Controller("diff-drive", cost, o)
    robot = mppi.DiffDrive()
    x = np.array([1.0, 1.0, 0.0], np.float32)
    start = math.hypot(9, 9)
    for _ in range(750):  # 15 s
        u, s = c.step(x)
        assert s.status == mppi.StepStatus.OK
        assert u.dtype == np.float32 and u.shape == (2,)
        assert -0.35 <= u[0] <= 0.5 and -0.5 <= u[1] <= 0.5
        x = robot.step(x, u, 0.02)
    # the benchmark's goal-angle term (goal yaw 0) keeps the heading near 0, so the robot runs
    # along x first; in 15 s it must still have closed on the goal (10, 10) by > 1 m
    assert math.hypot(10 - x[0], 10 - x[1]) < start - 1.0
    assert abs(x[2]) < 0.5
    assert c.nominal.shape == (100, 2)
    w = c.weights
    assert w.shape == (1024,) and abs(w.sum() - 1) < 1e-4
    assert c.step_index == 750


def test_same_seed_same_controls_and_errors():
    cmap = mppi.CostMap.load_npz(os.path.join(DATA, "autorally/maps/gazebo/gazebo_costmap.npz"))
    cost = mppi.AutoRallyCost(cmap)
    o = mppi.ControllerOptions()
    o.num_samples = 256
    a = mppi.Controller("single-track", cost, o)
    b = mppi.Controller("single-track", cost, o)
    o.seed = 99
    c = mppi.Controller("single-track", cost, o)
    x = a.model_state(mppi.VehicleState(x_m=-8.5, y_m=-8.9, yaw_rad=2.356, vx_mps=5.0))
    assert x.shape == (a.num_states,)
    ua, _ = a.step(x)
    ub, _ = b.step(x)
    uc, _ = c.step(x)
    assert np.array_equal(ua, ub)
    assert not np.array_equal(ua, uc)
    # a state with NaN: the safe control, never NaN
    bad = x.copy()
    bad[0] = np.nan
    u, s = a.step(bad)
    assert s.status == mppi.StepStatus.INVALID_STATE
    assert list(u) == list(o.safe_control)
    o.num_samples = 0
    with pytest.raises(mppi.Error, match="num_samples"):
        mppi.Controller("kinematic", cost, o)
    with pytest.raises(mppi.Error, match="unknown model"):
        mppi.Controller("tricycle", cost)
    with pytest.raises(mppi.Error, match="vehicle model"):
        mppi.Controller("diff-drive", cost)
    assert cost.evaluate(x, 0) == pytest.approx(cost.evaluate(x, 0))
    assert cmap.lookup(np.array([-8.5], np.float32), np.array([-8.9], np.float32))[0] == pytest.approx(0.0)


def test_cost_parameters_change_while_running():
    cmap = mppi.CostMap.load_npz(os.path.join(DATA, "autorally/maps/gazebo/gazebo_costmap.npz"))
    o = mppi.ControllerOptions()
    o.num_samples = 256
    o.num_threads = 1
    a = mppi.Controller("double-track", mppi.AutoRallyCost(cmap), o)  # any registered model
    params = mppi.AutoRallyCostParams()
    params.target_speed_mps = 9.0
    b = mppi.Controller("double-track", mppi.AutoRallyCost(cmap, params), o)
    x = a.model_state(mppi.VehicleState(x_m=-8.5, y_m=-8.9, yaw_rad=2.356, vx_mps=5.0))
    # a's cost changes before its first step: from then on it is b
    a.set_cost_param("target_speed_mps", 9.0)
    for _ in range(3):
        ua, _ = a.step(x)
        ub, _ = b.step(x)
        assert np.array_equal(ua, ub)
    with pytest.raises(mppi.Error, match="unknown cost parameter"):
        a.set_cost_param("target_speed", 9.0)
    with pytest.raises(mppi.Error, match="speed_weight"):
        a.set_cost_param("speed_weight", -1.0)
    ua, _ = a.step(x)
    ub, _ = b.step(x)
    assert np.array_equal(ua, ub)  # the refused changes changed nothing


def test_run_closed_loop_releases_the_gil():
    config = sim_config()
    config.laps = 1
    config.max_time_s = 4.0
    summary, counts = run_counting_main_thread(lambda: mppi.run_closed_loop(config))
    assert summary.sim_time_s == pytest.approx(4.0, abs=0.05)
    assert counts > 0  # 0 exactly when the call holds the GIL (gil_check.py)


def test_controller_variants_from_python():
    """The sampler, the adaptive temperature and the actuator chain are settable from Python and
    do what they say: the smooth sampler's draws change less from step to step than the Gaussian's,
    the temperature holds the effective sample size at its target, and a bad setting is refused."""
    cmap = mppi.CostMap.load_npz(os.path.join(DATA, "autorally/maps/gazebo/gazebo_costmap.npz"))
    cost = mppi.AutoRallyCost(cmap)

    def draws_step_change(kind):
        o = mppi.ControllerOptions()
        o.num_samples = 256
        o.num_threads = 1
        o.sampler.kind = kind
        o.temperature.ess_share = 0.1
        o.actuators = [mppi.ActuatorChannel(delay_s=0.04, lag_s=0.1, rate_per_s=5.0),
                       mppi.ActuatorChannel(rate_per_s=10.0)]
        c = mppi.Controller("single-track", cost, o)
        x = c.model_state(mppi.VehicleState(x_m=-8.5, y_m=-8.9, yaw_rad=2.356, vx_mps=5.0))
        u, s = c.step(x)
        assert s.status == mppi.StepStatus.OK
        assert abs(s.effective_sample_size / 25.6 - 1) <= 0.1 + 1e-3
        assert s.lambda_ > 0
        v = c.sampled_controls  # T x nu x K
        assert v.shape == (100, 2, 256)
        steer = v[:, 0, :]
        return float(np.mean(np.abs(np.diff(steer, axis=0))))

    assert draws_step_change(mppi.SamplerKind.SMOOTH) < 0.5 * draws_step_change(mppi.SamplerKind.GAUSSIAN)
    o = mppi.ControllerOptions()
    o.actuators = [mppi.ActuatorChannel(delay_s=-1.0), mppi.ActuatorChannel()]
    with pytest.raises(mppi.Error, match="delay_s"):
        mppi.Controller("single-track", cost, o)


def test_grip_adaptation_from_python():
    """The online grip adaptation is settable from Python: the step summary gives the fitted scale,
    a model without the lateral force parameter is refused by name where the model is to be
    scaled, and a bad setting is named."""
    cmap = mppi.CostMap.load_npz(os.path.join(DATA, "autorally/maps/gazebo/gazebo_costmap.npz"))
    cost = mppi.AutoRallyCost(cmap)
    o = mppi.ControllerOptions()
    o.num_samples = 256
    o.num_threads = 1
    o.force_adaptation.enabled = True
    c = mppi.Controller("single-track", cost, o)
    x = c.model_state(mppi.VehicleState(x_m=-8.5, y_m=-8.9, yaw_rad=2.356, vx_mps=5.0))
    for _ in range(3):
        u, s = c.step(x)
        assert s.status == mppi.StepStatus.OK
        assert 0.4 <= s.lateral_force_scale <= 1.5
    o.force_adaptation.scale_model = True
    with pytest.raises(mppi.Error, match="lateral_force_scale"):
        mppi.Controller("kinematic", cost, o)
    mppi.Controller("autorally-nn", cost, o)
    o.force_adaptation.memory_s = 0.0
    with pytest.raises(mppi.Error, match="memory_s"):
        mppi.Controller("single-track", cost, o)


def test_tube_variant_publishes_its_gains():
    """The tube variant's gains and nominal states reach Python with their shapes; the control
    sent is the plan's first control plus the first gain times the state error."""
    cmap = mppi.CostMap.load_npz(os.path.join(DATA, "autorally/maps/gazebo/gazebo_costmap.npz"))
    cost = mppi.AutoRallyCost(cmap)
    o = mppi.ControllerOptions()
    o.num_samples = 256
    o.num_threads = 1
    o.variant = "tube"
    o.tube_reset_distance = 5.0
    c = mppi.Controller("kinematic", cost, o)
    x = c.model_state(mppi.VehicleState(x_m=-8.5, y_m=-8.9, yaw_rad=2.356, vx_mps=5.0))
    u, s = c.step(x)
    assert s.feedback_applied and s.nominal_reset
    assert c.feedback_gains.shape == (100, 2, c.num_states)
    assert c.nominal_states.shape == (101, c.num_states)
    x_nom = c.nominal_states[1].copy()  # where the nominal state went
    x_meas = x_nom.copy()
    x_meas[0] += 0.1  # 10 cm off in x
    u, s = c.step(x_meas)
    assert not s.nominal_reset
    assert s.tube_distance == pytest.approx(0.1, rel=1e-3)
    with pytest.raises(mppi.Error, match="plain, tube or robust"):
        o.variant = "rmppi"


def test_robust_augmented_sampling_from_python():
    """Robust MPPI's augmented sampling is settable from Python: from the second step on the
    samples are also rolled out as the real car; the tube variant refuses it by name."""
    cmap = mppi.CostMap.load_npz(os.path.join(DATA, "autorally/maps/gazebo/gazebo_costmap.npz"))
    cost = mppi.AutoRallyCost(cmap)
    o = mppi.ControllerOptions()
    o.num_samples = 256
    o.num_threads = 1
    o.variant = "robust"
    o.robust_augmented_sampling = True
    o.robust_cost_bound = 5000.0
    c = mppi.Controller("kinematic", cost, o)
    x = c.model_state(mppi.VehicleState(x_m=-8.5, y_m=-8.9, yaw_rad=2.356, vx_mps=5.0))
    u, s = c.step(x)
    assert s.feedback_applied and not s.augmented_sampling
    x_meas = c.nominal_states[1].copy()
    x_meas[0] += 0.1
    u, s = c.step(x_meas)
    assert s.status == mppi.StepStatus.OK and s.augmented_sampling
    assert np.all(np.isfinite(u))
    o.variant = "tube"
    ok, why = o.is_valid(2)
    assert not ok and "robust_augmented_sampling needs the robust variant" in why
