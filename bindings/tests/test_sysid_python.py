"""pytest for the sysid part of the `mppi` module (bindings/sysid_py.cpp).

Oracles: the bifilar closed form computed here in Python; the ETH RC-car conversion redone here
from the raw CSV in the zip (documented conventions); the known truth of the simulated protocol;
and the C++ program `mppi-fit` ($MPPI_FIT_EXE, set by ctest) run on the same files, whose
estimate (parameters.csv) and diagnosis (report.json) the bindings must reproduce.
"""
import csv
import io
import json
import math
import os
import subprocess
import zipfile

import numpy as np
import pytest

import mppi
from gil_check import run_counting_main_thread

if not hasattr(mppi, "estimate_parameters"):
    pytest.skip("mppi built without the sysid part", allow_module_level=True)

FIT = os.environ.get("MPPI_FIT_EXE", "")
DATA = os.environ.get("MPPI_DATA_DIR") or mppi.data_dir()


def need_fit():
    if not FIT or not os.path.exists(FIT):
        pytest.skip("MPPI_FIT_EXE not set (run through ctest)")


# ---- bifilar pendulum ----

def test_bifilar_matches_closed_form():
    g = 9.81
    for m, T, r1, r2, d in [(21.88, 1.7, 0.3, 0.25, 1.5), (0.82, 0.9, 0.12, 0.12, 0.8), (5.0, 2.3, 0.4, 0.1, 2.0)]:
        h = math.sqrt(d * d - (r1 - r2) ** 2)
        assert mppi.bifilar_height(d, r1, r2) == pytest.approx(h, rel=1e-12)
        closed = m * g * r1 * r2 * T * T / (4 * math.pi ** 2 * h)
        i = mppi.bifilar_inertia(m, T, r1, r2, h)
        assert i == pytest.approx(closed, rel=1e-12)
        assert mppi.bifilar_period(i, m, r1, r2, h) == pytest.approx(T, rel=1e-12)
        par = m * g * r1 * r1 * T * T / (4 * math.pi ** 2 * d)
        assert mppi.bifilar_inertia_parallel(m, T, r1, d) == pytest.approx(par, rel=1e-12)
    with pytest.raises(mppi.Error):
        mppi.bifilar_inertia(-1.0, 1.0, 0.1, 0.1, 1.0)
    with pytest.raises(mppi.Error):
        mppi.bifilar_height(0.1, 0.3, 0.1)  # |R1 - R2| >= d


def test_bifilar_paper_table():
    rows = mppi.bifilar_table()
    assert [r["axis"] for r in rows] == ["I_x", "I_y", "I_z", "I_f", "I_r"]
    for r in rows:
        b, d, T, m = r["half_separation_m"], r["wire_length_m"], r["period_s"], r["mass_kg"]
        closed = m * 9.81 * b * b * T * T / (4 * math.pi ** 2 * d)
        assert r["computed_kgm2"] == pytest.approx(closed, rel=1e-12)
        assert r["relative_diff"] == pytest.approx(closed / r["printed_kgm2"] - 1, abs=1e-12)
        assert r["min_kgm2"] <= closed <= r["max_kgm2"]
        # the period that reproduces the printed value, through the closed form
        assert m * 9.81 * b * b * r["period_for_printed_s"] ** 2 / (4 * math.pi ** 2 * d) == \
            pytest.approx(r["printed_kgm2"], rel=1e-9)


# ---- real recordings ----

def test_load_real_eth_recording_matches_python_conversion():
    zpath = os.path.join(DATA, "real", "eth_lasgroup_rccar.zip")
    with zipfile.ZipFile(zpath) as z:
        rows = list(csv.DictReader(io.StringIO(z.read("train_1.csv").decode())))
    raw = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    rec = mppi.load_recording(zpath + ":train_1.csv")
    c = rec["columns"]
    assert set(["t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle"]) <= set(rec["column_names"])
    yaw = np.unwrap(raw["theta_rad"])
    np.testing.assert_allclose(c["t"], raw["t_nominal_s"], atol=1e-9)
    np.testing.assert_allclose(c["x"], raw["x_m"], atol=1e-9)
    np.testing.assert_allclose(c["yaw"], yaw, atol=1e-9)
    vx = np.cos(yaw) * raw["vx_world_mps"] + np.sin(yaw) * raw["vy_world_mps"]
    vy = -np.sin(yaw) * raw["vx_world_mps"] + np.cos(yaw) * raw["vy_world_mps"]
    np.testing.assert_allclose(c["vx"], vx, atol=1e-9)
    np.testing.assert_allclose(c["vy"], vy, atol=1e-9)
    omega = np.where(np.abs(raw["omega_radps"]) > 20.0, np.nan, raw["omega_radps"])
    np.testing.assert_allclose(c["yaw_rate"], omega, atol=1e-9)  # NaN where the glitches were
    np.testing.assert_allclose(c["steer"], raw["steer_cmd"], atol=1e-9)
    # the data-folder shorthand and the explicit converter give the same recording
    same = mppi.convert_real_recording("real/eth_lasgroup_rccar.zip:train_1.csv", source="eth")
    np.testing.assert_array_equal(same["columns"]["vx"], c["vx"])
    assert "train_1.csv" in mppi.zip_members(zpath)
    with pytest.raises(mppi.Error, match="nope.csv"):
        mppi.load_recording(zpath + ":nope.csv")


# ---- protocol + estimation ----

NAMES = ["mass_kg", "yaw_inertia_kgm2", "cg_height_m", "tyre.D"]
TRUTH = {"mass_kg": 20.6, "yaw_inertia_kgm2": 1.02, "cg_height_m": 0.096, "tyre.D": 0.92}
# the tuning of the C++ test (tests/sysid/test_protocol_estimation.cpp)
TUNING = dict(process_scale=0.1, walk_std=0.001)


@pytest.fixture(scope="module")
def protocol_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("protocol")
    run = mppi.run_protocol(overrides=TRUTH, manoeuvre_duration_s=8.0, validation_duration_s=6.0,
                            out_dir=str(d))
    return d, run


def test_protocol_recordings(protocol_dir):
    d, run = protocol_dir
    tr, val, truth = run["training"], run["validation"], run["truth"]
    t = tr["columns"]["t"]
    assert len(t) == 40 * 50 and t[0] == 0.0 and t[-1] < 40.0
    assert len(val["columns"]["t"]) == 6 * 50
    assert sorted(set(tr["columns"]["segment"])) == [1, 2, 3, 4, 5]
    # measured = truth + small sensor noise
    n = len(t)
    err = tr["columns"]["vx"] - truth["columns"]["vx"][:n]
    assert 0.02 < np.std(err) < 0.1  # velocity_noise_mps = 0.05
    for f in ["train.csv", "validation.csv", "truth.csv", "truth.yaml"]:
        assert (d / f).exists()
    back = mppi.read_recording(str(d / "train.csv"))
    np.testing.assert_allclose(back["columns"]["vx"], tr["columns"]["vx"], rtol=1e-5, atol=1e-6)


@pytest.fixture(scope="module")
def py_estimate(protocol_dir):
    d, _ = protocol_dir
    return mppi.estimate_parameters(str(d / "train.csv"), model="full-vehicle", estimate=NAMES,
                                    truth_file=str(d / "truth.yaml"), **TUNING)


def test_estimation_recovers_truth(protocol_dir, py_estimate):
    r = py_estimate
    assert r["names"] == NAMES
    for i, n in enumerate(NAMES):
        assert r["values"][n] == pytest.approx(TRUTH[n], rel=0.02), n
        assert r["truth"][i] == pytest.approx(TRUTH[n], rel=1e-9)
        h = r["history"][n]
        assert h.shape == r["t"].shape and h[-1] == pytest.approx(r["estimate"][i], rel=1e-9)
        assert abs(r["initial"][i] / TRUTH[n] - 1) > 0.01 or n == "tyre.D"  # it had to move
    assert r["rejected_steps"] == 0
    conv = r["convergence_s"]
    assert np.all(np.isfinite(conv["final_5pct"])) and np.all(conv["final_5pct"] < 40.0)
    # convergence time recomputed from the history: last exit from the 5% band around the final
    for i, n in enumerate(NAMES):
        h, t = r["history"][n], r["t"]
        out = np.nonzero(np.abs(h - r["estimate"][i]) > 0.05 * abs(r["estimate"][i]))[0]
        expect = t[out[-1] + 1] - t[0] if len(out) else 0.0
        assert conv["final_5pct"][i] == pytest.approx(expect, abs=1e-9), n
    # the estimated model predicts the held-out segment better than the nominal one
    val = str(protocol_dir[0] / "validation.csv")
    est = mppi.validate_parameters(val, model="full-vehicle", values=r["values"])
    nom = mppi.validate_parameters(val, model="full-vehicle")
    k = est["channels"].index("yaw_rate")
    assert est["open_loop_rms"][k] < nom["open_loop_rms"][k]


def test_estimation_matches_cli(protocol_dir, py_estimate, tmp_path):
    need_fit()
    d, _ = protocol_dir
    out = tmp_path / "est"
    subprocess.run([FIT, "estimate", str(d / "train.csv"), "--model", "full-vehicle", "--estimate", ",".join(NAMES),
                    "--process-scale", "0.1", "--walk-std", "0.001", "--truth", str(d / "truth.yaml"),
                    "--out", str(out)], check=True, capture_output=True)
    with open(out / "parameters.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["name"] for r in rows] == NAMES
    conv = py_estimate["convergence_s"]
    for i, row in enumerate(rows):
        assert float(row["estimate"]) == pytest.approx(py_estimate["estimate"][i], rel=1e-5)
        assert float(row["std"]) == pytest.approx(py_estimate["std"][i], rel=1e-5)
        assert float(row["converged_5pct_s"]) == pytest.approx(conv["final_5pct"][i], abs=1e-3)
        assert float(row["converged_truth_5pct_s"]) == pytest.approx(conv["truth_5pct"][i], abs=1e-3)


def test_estimation_errors(protocol_dir):
    d, _ = protocol_dir
    with pytest.raises(mppi.Error, match="no_such_param"):
        mppi.estimate_parameters(str(d / "train.csv"), model="full-vehicle", estimate=["no_such_param"])
    with pytest.raises(mppi.Error, match="model"):
        mppi.estimate_parameters(str(d / "train.csv"), model="bicycle")


def test_protocol_releases_the_gil():
    result, counts = run_counting_main_thread(
        lambda: mppi.run_protocol(manoeuvre_duration_s=6.0, validation_duration_s=2.0))
    assert len(result["training"]["columns"]["t"]) > 0
    assert counts > 0  # 0 exactly when the call holds the GIL (gil_check.py)


# ---- diagnose ----

@pytest.fixture(scope="module")
def synth_log(tmp_path_factory):
    d = tmp_path_factory.mktemp("diag")
    path = str(d / "steer_delay.csv")
    rec, ids = mppi.diagnose_synth_open_loop("steer_delay_s=0.08", seed=21, duration_s=12.0, out_path=path)
    assert ids == ["steer_delay"]
    return d, path, rec


# The candidates: the steering's forms of dynamics, its gain and trim (and the joint of the two),
# the drag and the throttle lag; the same list for the bindings and the program.
DIAG_EFFECTS = ["steer_delay", "steer_lag", "steer_rate_limit", "steer_backlash", "steer_gain", "steer_offset",
                "aero_drag", "throttle_lag"]


def test_diagnose_names_hidden_effect_and_matches_cli(synth_log):
    d, path, rec = synth_log
    assert len(rec["columns"]["t"]) == 12 * 50
    out_py = d / "py"
    r = mppi.diagnose(path, effects=DIAG_EFFECTS, out_dir=str(out_py), plots=False)
    assert r["selected"] and r["selected"][0] == "steer_delay"
    delay = [p for p in r["final_params"] if p["name"] == "steer_delay_s"]
    assert delay and delay[0]["value"] == pytest.approx(0.08, abs=0.02)
    assert r["headline_after"] < 0.5 * r["headline_before"]
    assert (out_py / "report.json").exists() and (out_py / "report.md").exists()
    with open(out_py / "report.json") as f:
        assert json.load(f)["selected"] == r["selected"]
    need_fit()
    out_cli = d / "cli"
    subprocess.run([FIT, "diagnose", "--log", path, "--effects", ",".join(DIAG_EFFECTS), "--out", str(out_cli),
                    "--no-plots"], check=True, capture_output=True)
    with open(out_cli / "report.json") as f:
        cli = json.load(f)
    py = dict(r["report"])
    for j in (cli, py):
        j.pop("model_file", None)  # the output folders differ
    assert py == cli


def test_diagnose_clean_recording_names_nothing(tmp_path):
    path = str(tmp_path / "clean.csv")
    mppi.diagnose_synth_open_loop("", seed=3, duration_s=40.0, out_path=path)
    r = mppi.diagnose(path, effects=["steer_delay", "aero_drag", "steer_offset"])
    assert r["selected"] == []
    with pytest.raises(mppi.Error, match="no_such_effect"):
        mppi.diagnose(path, effects=["no_such_effect"])
    # A nominal model without an effects version is refused by name.
    with pytest.raises(mppi.Error, match="diff-drive"):
        mppi.diagnose(path, model="diff-drive")
    # The double-track nominal on a single-track recording: runs, reports its model.
    r = mppi.diagnose(path, model="double-track", effects=["steer_delay"])
    assert r["report"]["model"] == "double-track"
