"""A grid file: the tasks of a sweep as YAML (or JSON).

    kind: closed_loop            # closed_loop | sim_process | evidence_case | fit_command
    base: {track: gazebo, laps: 2, threads: 1, model: single-track, plant: single-track}
    grid:                        # every combination of these values, over the base
      seed: [1, 2, 3]
      speed: [7, 8]
    tasks:                       # and/or tasks listed one by one (over the base too)
      - {seed: 9, track: marietta}
"""
import itertools
import json

import yaml

from ..errors import ToolError


def expand(spec, where='grid'):
    """(kind, [settings]) of a grid spec."""
    if not isinstance(spec, dict) or 'kind' not in spec:
        raise ToolError(f'{where}: expected a mapping with kind, base, grid and/or tasks')
    unknown = set(spec) - {'kind', 'base', 'grid', 'tasks'}
    if unknown:
        raise ToolError(f'{where}: unknown keys {sorted(unknown)} (kind, base, grid, tasks)')
    base = spec.get('base') or {}
    grid = spec.get('grid') or {}
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ToolError(f'{where}: grid.{key} must be a non-empty list of values')
    tasks = []
    if grid:
        keys = list(grid)
        for combo in itertools.product(*(grid[k] for k in keys)):
            tasks.append({**base, **dict(zip(keys, combo))})
    for i, extra in enumerate(spec.get('tasks') or []):
        if not isinstance(extra, dict):
            raise ToolError(f'{where}: tasks[{i}] must be a mapping of settings')
        tasks.append({**base, **extra})
    if not tasks:
        tasks = [dict(base)] if base else []
    if not tasks:
        raise ToolError(f'{where}: no tasks (give grid, tasks or base)')
    return spec['kind'], tasks


def read_grid_file(path):
    try:
        with open(path) as f:
            spec = json.load(f) if path.endswith('.json') else yaml.safe_load(f)
    except OSError as e:
        raise ToolError(f'{path}: cannot read the grid file ({e.strerror})') from None
    except (yaml.YAMLError, json.JSONDecodeError) as e:
        raise ToolError(f'{path}: not valid YAML/JSON ({e})') from None
    return expand(spec, path)
