"""mppi-sim settings as a dict of run-file keys (the long flags without their dashes:
{'track': 'gazebo', 'samples': 1024, 'noise-std': [0.2, 0.3]}), written as the YAML run file that
`mppi-sim --config FILE` reads. Keys `cost.NAME` are AutoRally cost weights (the keys of
data/config/autorally_cost.yaml); they go to a cost file that the run file names (cost-config)."""
import os

import yaml

from .errors import ToolError

COST_PREFIX = 'cost.'
COST_KEYS = ('track_weight', 'speed_weight', 'crash_weight', 'slip_weight', 'target_speed_mps', 'crash_discount',
             'boundary_threshold', 'max_roll_rad', 'max_yaw_rate_radps', 'slip_min_speed_mps')


def split_cost(settings):
    """(run settings without the cost keys, {cost key: value}); ToolError for an unknown cost key."""
    run, cost = {}, {}
    for key, value in settings.items():
        if key.startswith(COST_PREFIX):
            name = key[len(COST_PREFIX):]
            if name not in COST_KEYS:
                raise ToolError(f'setting {key!r}: not an AutoRally cost weight (known: {", ".join(COST_KEYS)})')
            cost[name] = value
        else:
            run[key] = value
    return run, cost


def yaml_value(value):
    """A setting as mppi-sim reads it: lists comma-separated, numbers and booleans as they are."""
    if isinstance(value, (list, tuple)):
        return ','.join(repr(float(v)) if isinstance(v, float) else str(v) for v in value)
    return value


def write_cost_file(path, cost, base_file=''):
    """The cost weights `cost` over those of base_file (or the library's defaults) as a cost YAML."""
    merged = {}
    if base_file:
        with open(base_file) as f:
            merged.update(yaml.safe_load(f) or {})
    merged.update(cost)
    with open(path, 'w') as f:
        f.write('# AutoRally cost weights (costs/autorally_cost.hpp); missing keys keep their defaults.\n')
        yaml.safe_dump(merged, f, sort_keys=False, default_flow_style=False)
    return path


def write_run_file(path, settings, comment='', cost_path=None):
    """Writes settings as an mppi-sim run file at path. Cost keys go to cost_path (default:
    <path without .yaml>_cost.yaml), named by the run file's cost-config with the path as given
    (relative paths are read from mppi-sim's working directory). Returns (run file, cost file or None)."""
    run, cost = split_cost(settings)
    cost_file = None
    if cost:
        cost_file = cost_path or os.path.splitext(path)[0] + '_cost.yaml'
        write_cost_file(cost_file, cost, run.get('cost-config', ''))
        run['cost-config'] = cost_file
    with open(path, 'w') as f:
        for line in comment.splitlines():
            f.write(f'# {line}\n' if line else '#\n')
        yaml.safe_dump({k: yaml_value(v) for k, v in run.items()}, f, sort_keys=False, default_flow_style=False)
    return path, cost_file


def read_run_file(path):
    """The settings of a run file, with its cost file's weights as cost.* keys."""
    with open(path) as f:
        run = yaml.safe_load(f) or {}
    if not isinstance(run, dict):
        raise ToolError(f'{path}: a run file is a YAML mapping of mppi-sim keys')
    settings = dict(run)
    if run.get('cost-config'):
        with open(run['cost-config']) as f:
            settings.update({COST_PREFIX + k: v for k, v in (yaml.safe_load(f) or {}).items()})
    return settings


def flags_to_settings(flags):
    """['--ess-target', '0.02', '--clockwise'] -> {'ess-target': '0.02', 'clockwise': True}."""
    settings, i = {}, 0
    while i < len(flags):
        flag = flags[i]
        if not flag.startswith('--'):
            raise ToolError(f'{flags}: expected a --flag at {flag!r}')
        if i + 1 < len(flags) and not flags[i + 1].startswith('--'):
            settings[flag[2:]] = flags[i + 1]
            i += 2
        else:
            settings[flag[2:]] = True
            i += 1
    return settings


def settings_to_flags(settings):
    """The inverse: {'laps': 2, 'clockwise': True} -> ['--laps', '2', '--clockwise']."""
    flags = []
    for key, value in settings.items():
        if value is True:
            flags.append(f'--{key}')
        elif value is not False:
            flags += [f'--{key}', str(yaml_value(value))]
    return flags
