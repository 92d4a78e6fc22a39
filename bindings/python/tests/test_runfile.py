"""The run-file writer: what it writes loads in mppi-sim (--dump-config gives the settings back),
and the run file drives the same run as the in-process adapter the tuner's trials use."""
import json
import os
import subprocess

import numpy as np
import pytest
import yaml

from mppi_tools import paths, runfile
from mppi_tools.sweep import ClosedLoop, SimProcess

SETTINGS = {'model': 'single-track', 'plant': 'single-track', 'track': 'gazebo', 'laps': 1, 'samples': 256,
            'horizon': 50, 'threads': 1, 'seed': 3, 'speed': 8.7, 'ess-target': 0.031, 'noise-std': [0.21, 0.43],
            'smoothing': 9, 'sampler': 'lowpass', 'sampler-cutoff': 4.5,
            'cost.track_weight': 37.5, 'cost.speed_weight': 9.25, 'cost.slip_weight': 0.8}


def f32(x):
    return float(np.float32(x))


def test_the_written_run_file_loads_in_mppi_sim_and_gives_the_settings_back(tmp_path):
    run_yaml, cost_yaml = runfile.write_run_file(str(tmp_path / 'tuned.yaml'), SETTINGS, comment='a test\nfile')
    assert cost_yaml == str(tmp_path / 'tuned_cost.yaml')
    dump = subprocess.run([paths.program('mppi-sim'), '--config', run_yaml, '--dump-config'], capture_output=True,
                          text=True, cwd=paths.REPO_ROOT)
    assert dump.returncode == 0, dump.stderr
    effective = yaml.safe_load(dump.stdout)
    for key in ('model', 'plant', 'track', 'laps', 'samples', 'horizon', 'threads', 'seed', 'smoothing', 'sampler'):
        assert effective[key] == SETTINGS[key], key
    for key in ('speed', 'ess-target', 'sampler-cutoff'):
        assert f32(effective[key]) == f32(SETTINGS[key]), key
    assert [f32(v) for v in str(effective['noise-std']).split(',')] == [f32(0.21), f32(0.43)]
    assert effective['cost-config'] == cost_yaml
    with open(cost_yaml) as f:
        cost = yaml.safe_load(f)
    assert cost == {'track_weight': 37.5, 'speed_weight': 9.25, 'slip_weight': 0.8}
    assert runfile.read_run_file(run_yaml) == {**{k: v for k, v in SETTINGS.items() if k != 'noise-std'},
                                               'noise-std': '0.21,0.43', 'cost-config': cost_yaml}


def test_mppi_sim_with_the_run_file_drives_the_run_of_the_module(tmp_path):
    pytest.importorskip('mppi')
    in_process = ClosedLoop()(SETTINGS)
    run_yaml, _ = runfile.write_run_file(str(tmp_path / 'tuned.yaml'), SETTINGS)
    by_process = SimProcess(str(tmp_path / 'runs'))({'config': run_yaml})
    assert in_process['laps_completed'] == 1
    assert json.dumps(in_process, sort_keys=True) == json.dumps({**by_process, 'wall_optimizer_ms_p50': in_process[
        'wall_optimizer_ms_p50']}, sort_keys=True)


def test_a_bad_setting_in_the_run_file_is_refused_by_mppi_sim(tmp_path):
    run_yaml, _ = runfile.write_run_file(str(tmp_path / 'bad.yaml'), {'samplez': 3})
    done = subprocess.run([paths.program('mppi-sim'), '--config', run_yaml, '--dump-config'], capture_output=True,
                          text=True)
    assert done.returncode != 0 and 'samplez' in done.stderr + done.stdout


def test_flags_and_settings_round_trip():
    flags = ['--ess-target', '0.02', '--actuator-model', 'plant', '--clockwise']
    settings = runfile.flags_to_settings(flags)
    assert settings == {'ess-target': '0.02', 'actuator-model': 'plant', 'clockwise': True}
    assert runfile.settings_to_flags(settings) == flags
