"""mppi-tune: the parameter space refuses what it does not know; a tiny study (2 trials, one short
run each) writes its figures and a run file that mppi-sim loads with the best trial's settings."""
import json
import os
import subprocess

import pandas as pd
import pytest
import yaml

from mppi_tools import paths
from mppi_tools.errors import ToolError
from mppi_tools.tune import objective, space
from mppi_tools.tune.cli import main as tune_main

pytest.importorskip('optuna')


def test_unknown_and_conflicting_parameters_are_refused():
    with pytest.raises(ToolError, match=r"unknown \['gain'\]"):
        space.select(['lambda', 'gain'])
    with pytest.raises(ToolError, match='exclude each other'):
        space.select(['lambda', 'ess-target'])
    with pytest.raises(ToolError, match='sampler-cutoff needs sampler'):
        space.select(['sampler-cutoff'])
    with pytest.raises(ToolError, match='speed=LO:HI with LO < HI'):
        space.select(['speed'], ['speed=9:7'])
    assert space.select(['speed'], ['speed=7:9'])[0].high == 9.0


def test_an_empty_search_space_is_refused(tmp_path, capsys):
    with pytest.raises(ToolError, match='--params: no parameter to tune'):
        space.select([])
    with pytest.raises(ToolError, match='--params smoothing,actuator-model: each has one value left'):
        space.select(['smoothing', 'actuator-model'], ['smoothing=5', 'actuator-model=none'])
    assert len(space.select(['smoothing', 'speed'], ['smoothing=5'])) == 2  # speed is still free
    with pytest.raises(ToolError, match='--fixed speed=8: --params speed tunes that setting'):
        space.check_fixed(space.select(['speed']), {'speed': 8})
    with pytest.raises(ToolError, match='--fixed noise-std=.*--params noise-throttle'):
        space.check_fixed(space.select(['noise-throttle']), {'noise-std': [0.2, 0.3]})
    # Through the command line: refused by name before a study is made or a run driven.
    assert tune_main(['run', '--serial', '--params', '', '--out', str(tmp_path / 'out')]) == 2
    assert '--params: no parameter to tune (an empty search space)' in capsys.readouterr().err
    assert tune_main(['run', '--serial', '--params', 'speed', '--fixed', 'speed=8', '--out', str(tmp_path)]) == 2
    assert "--fixed speed=8: --params speed tunes that setting" in capsys.readouterr().err
    assert not os.path.exists(tmp_path / 'out')


def test_noise_channels_go_to_noise_std():
    params = space.select(['noise-steer', 'noise-throttle'])
    assert space.apply({}, params, {'noise-steer': 0.2, 'noise-throttle': 0.5}) == {'noise-std': [0.2, 0.5]}


def test_a_crash_makes_settings_infeasible():
    clean = {'crashes': 0, 'stalls': 0, 'finished': True, 'mean_lap_over_limit': 1.3}
    assert objective.score([clean, {**clean, 'mean_lap_over_limit': 1.5}]) == (pytest.approx(1.4), True, 0)
    value, feasible, incidents = objective.score([clean, {**clean, 'crashes': 2}])
    assert not feasible and incidents == 2 and value > 10


def test_a_tiny_study_writes_a_run_file_mppi_sim_loads(tmp_path):
    pytest.importorskip('mppi')
    out = str(tmp_path / 'tune')
    rc = tune_main(['run', '--serial', '--trials', '2', '--tracks', 'gazebo', '--seeds', '1', '--laps', '1',
                    '--params', 'speed,track-weight', '--range', 'speed=6:7', '--fixed', 'samples=256',
                    '--fixed', 'horizon=50', '--out', out])
    assert rc == 0
    trials = pd.read_csv(os.path.join(out, 'trials.csv'))
    assert len(trials) == 2 and trials['feasible'].all()
    best = trials.sort_values(['value', 'number']).iloc[0]
    for name in ('history.png', 'history.json', 'importance.csv', 'trials.csv', 'best.yaml', 'best_cost.yaml'):
        assert os.path.exists(os.path.join(out, name)), name
    dump = subprocess.run([paths.program('mppi-sim'), '--config', os.path.join(out, 'best.yaml'), '--dump-config'],
                          capture_output=True, text=True, cwd=paths.REPO_ROOT)
    assert dump.returncode == 0, dump.stderr
    effective = yaml.safe_load(dump.stdout)
    settings = json.loads(best['settings'])
    assert effective['speed'] == best['param.speed'] == settings['speed']  # the value the trial ran
    assert effective['samples'] == 256 and effective['model'] == 'single-track'
    with open(effective['cost-config']) as f:
        assert yaml.safe_load(f)['track_weight'] == best['param.track-weight']
