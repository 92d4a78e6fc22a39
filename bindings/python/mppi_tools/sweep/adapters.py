"""Task adapters: callables settings -> figures, picklable, so that Dask workers run them.

- ClosedLoop: a closed-loop run in the worker's process through the Python module
  (mppi.run_closed_loop); settings are mppi-sim run-file keys (and cost.* weights).
- SimProcess: the same settings through an mppi-sim process with a run folder
  (run.yaml, log.csv, track.png, summary.json).
- EvidenceCase: one case of the evidence grid (mppi-fit diagnose sweep --generator independent
  --cases LABEL): a recording of the independent generator and its diagnosis.
- FitCommand: any mppi-fit command (diagnose, calibrate, ...) with a run folder; the figures
  are the numbers of a JSON file it writes there.
"""
import json
import os
import subprocess
import tempfile

import yaml

from .. import paths, runfile
from ..errors import ToolError
from .figures import run_figures

# mppi-sim's own defaults that differ from the library's ClosedLoopConfig (cli/sim_command_line.cpp).
SIM_DEFAULTS = {'smoothing': 5}


def _number(key, value, kind=float):
    try:
        return kind(value)
    except (TypeError, ValueError):
        raise ToolError(f'setting {key!r}: expected a number, got {value!r}') from None


def _floats(key, value):
    items = value.split(',') if isinstance(value, str) else list(value)
    return [_number(key, v) for v in items]


def _bool(key, value):
    if isinstance(value, bool):
        return value
    if str(value).lower() in ('true', '1', 'yes'):
        return True
    if str(value).lower() in ('false', '0', 'no'):
        return False
    raise ToolError(f'setting {key!r}: expected true or false, got {value!r}')


def _sampler(c, key, value):
    import mppi
    kinds = {'gaussian': mppi.SamplerKind.GAUSSIAN, 'lowpass': mppi.SamplerKind.LOW_PASS,
             'smooth': mppi.SamplerKind.SMOOTH}
    if value not in kinds:
        raise ToolError(f'setting {key!r}: gaussian, lowpass or smooth, got {value!r}')
    c.controller.sampler.kind = kinds[value]


# Run-file key -> how it sets mppi.ClosedLoopConfig (the keys mppi-sim's run file has).
_SETTERS = {
    'track': lambda c, k, v: setattr(c, 'track', str(v)),
    'clockwise': lambda c, k, v: setattr(c, 'clockwise', _bool(k, v)),
    'model': lambda c, k, v: setattr(c, 'model', str(v)),
    'plant': lambda c, k, v: setattr(c, 'plant', str(v)),
    'speed': lambda c, k, v: setattr(c, 'target_speed_mps', _number(k, v)),
    'laps': lambda c, k, v: setattr(c, 'laps', _number(k, v, int)),
    'max-time': lambda c, k, v: setattr(c, 'max_time_s', _number(k, v)),
    'stall-timeout': lambda c, k, v: setattr(c, 'stall_timeout_s', _number(k, v)),
    'samples': lambda c, k, v: setattr(c.controller, 'num_samples', _number(k, v, int)),
    'horizon': lambda c, k, v: setattr(c.controller, 'horizon', _number(k, v, int)),
    'iterations': lambda c, k, v: setattr(c.controller, 'iterations', _number(k, v, int)),
    'warm-start-iterations': lambda c, k, v: setattr(c.controller, 'warm_start_iterations', _number(k, v, int)),
    'lambda': lambda c, k, v: setattr(c.controller, 'lambda_', _number(k, v)),
    'noise-std': lambda c, k, v: setattr(c.controller, 'noise_std', _floats(k, v)),
    'smoothing': lambda c, k, v: setattr(c.controller, 'smoothing_window', _number(k, v, int)),
    'sampler': _sampler,
    'sampler-cutoff': lambda c, k, v: setattr(c.controller.sampler, 'cutoff_hz', _number(k, v)),
    'smooth-time': lambda c, k, v: setattr(c.controller.sampler, 'smooth_time_s', _number(k, v)),
    'ess-target': lambda c, k, v: setattr(c.controller.temperature, 'ess_share', _number(k, v)),
    'lambda-min': lambda c, k, v: setattr(c.controller.temperature, 'lambda_min', _number(k, v)),
    'lambda-max': lambda c, k, v: setattr(c.controller.temperature, 'lambda_max', _number(k, v)),
    'variant': lambda c, k, v: setattr(c.controller, 'variant', str(v)),
    'tube-reset': lambda c, k, v: setattr(c.controller, 'tube_reset_distance', _number(k, v)),
    'robust-margin': lambda c, k, v: setattr(c.controller, 'robust_cost_margin', _number(k, v)),
    'robust-augmented': lambda c, k, v: setattr(c.controller, 'robust_augmented_sampling', _bool(k, v)),
    'robust-cost-bound': lambda c, k, v: setattr(c.controller, 'robust_cost_bound', _number(k, v)),
    'actuator-model': lambda c, k, v: setattr(c, 'actuator_model', str(v)),
    'seed': lambda c, k, v: setattr(c.controller, 'seed', _number(k, v, int)),
    'threads': lambda c, k, v: setattr(c.controller, 'num_threads', _number(k, v, int)),
    'cost-config': lambda c, k, v: setattr(c, 'cost_params_yaml', str(v)),
    'plant-params': lambda c, k, v: setattr(c, 'plant_params_yaml', str(v)),
    'model-params': lambda c, k, v: setattr(c, 'model_params_yaml', str(v)),
    'network': lambda c, k, v: setattr(c, 'network_npz', str(v)),
    'steer-rate-limit': lambda c, k, v: setattr(c.actuators, 'steer_rate_per_s', _number(k, v)),
    'throttle-rate-limit': lambda c, k, v: setattr(c.actuators, 'throttle_rate_per_s', _number(k, v)),
    'backend': lambda c, k, v: None if v == 'cpu' else _refuse_backend(k, v),
}


def _refuse_backend(key, value):
    raise ToolError(f'setting {key!r}: the Python module runs on the CPU backend only (got {value!r}); '
                    f'use the sim_process adapter for {value}')


class ClosedLoop:
    """A closed-loop run in this process (the Python module `mppi`): mppi-sim's defaults, then the settings."""
    kind = 'closed_loop'

    def config(self, settings, cost_file=None):
        import mppi
        run, cost = runfile.split_cost({**SIM_DEFAULTS, **settings})
        c = mppi.ClosedLoopConfig()
        c.progress = False
        c.controller.smoothing_order = 2  # mppi-sim's, with its smoothing window
        for key, value in run.items():
            setter = _SETTERS.get(key)
            if setter is None:
                raise ToolError(f'setting {key!r}: not a closed-loop setting (known: {", ".join(sorted(_SETTERS))}, '
                                f'cost.*)')
            setter(c, key, value)
        if cost:
            if cost_file is None:
                raise ToolError('cost.* settings need a cost file to write')
            c.cost_params_yaml = runfile.write_cost_file(cost_file, cost, c.cost_params_yaml)
        return c

    def __call__(self, settings):
        import mppi
        with tempfile.TemporaryDirectory(prefix='mppi_closed_loop_') as tmp:
            config = self.config(settings, os.path.join(tmp, 'cost.yaml'))
            summary = json.loads(mppi.run_closed_loop(config).to_json())
        return run_figures(summary)


class SimProcess:
    """An mppi-sim process per task: DIR/run.yaml (the settings as a run file), DIR/mppi_sim.log and
    mppi-sim's outputs. DIR is the setting `out` (a path all workers can reach) or
    <out_root>/<the task's key>. The setting `config` names a run file of its own instead: mppi-sim
    --config FILE with the other settings as flags (cost.* weights cannot be given then)."""
    kind = 'sim_process'

    def __init__(self, out_root, bin_dir=None, cwd=None):
        self.out_root = os.path.abspath(out_root)
        self.binary = paths.program('mppi-sim', bin_dir)
        self.cwd = cwd or paths.REPO_ROOT

    def __call__(self, settings):
        from .keys import task_key
        settings = dict(settings)
        out = settings.pop('out', None) or os.path.join(self.out_root, task_key(self.kind, settings))
        out = os.path.join(self.cwd, out)
        os.makedirs(out, exist_ok=True)
        config = settings.pop('config', None)
        if config:  # a run file of its own, the other settings as flags over it
            command = [self.binary, '--config', config, *runfile.settings_to_flags(settings)]
        else:
            run_yaml, _ = runfile.write_run_file(os.path.join(out, 'run.yaml'), settings,
                                                 cost_path=os.path.join(out, 'cost.yaml'))
            command = [self.binary, '--config', run_yaml]
        command += ['--out', out, '--quiet']
        with open(os.path.join(out, 'mppi_sim.log'), 'w') as log:
            log.write(' '.join(command) + '\n')
            log.flush()
            rc = subprocess.call(command, cwd=self.cwd, stdout=log, stderr=subprocess.STDOUT)
        summary_path = os.path.join(out, 'summary.json')
        if not os.path.exists(summary_path):  # exit 1 with a summary: a run that did not finish its laps
            raise ToolError(f'mppi-sim exited {rc} without a summary (see {out}/mppi_sim.log)')
        with open(summary_path) as f:
            return run_figures(json.load(f))


# The figures of an evidence case: keys of its runs.jsonl line (diagnose/evidence_sweep.cpp).
EVIDENCE_FIGURES = ('track', 'direction', 'driver', 'crashes', 'named', 'right', 'right_strict', 'wrong',
                    'heldout_1s_nrmse_clean_before', 'heldout_1s_nrmse_clean_after', 'reduction')


class EvidenceCase:
    """One case of the evidence grid, by label (settings: case, and the grid's options as
    mppi-fit flags without dashes, e.g. reduced: true, duration: 60)."""
    kind = 'evidence_case'

    def __init__(self, out_root, bin_dir=None):
        self.out_root = os.path.abspath(out_root)
        self.binary = paths.program('mppi-fit', bin_dir)

    def __call__(self, settings):
        settings = dict(settings)
        label = settings.pop('case')
        out = os.path.join(self.out_root, label)
        os.makedirs(out, exist_ok=True)
        command = [self.binary, 'diagnose', 'sweep', '--generator', 'independent', '--cases', label,
                   '--out', out] + runfile.settings_to_flags(settings)
        with open(os.path.join(out, 'mppi_fit.log'), 'w') as log:
            log.write(' '.join(command) + '\n')
            log.flush()
            rc = subprocess.call(command, cwd=paths.REPO_ROOT, stdout=log, stderr=subprocess.STDOUT)
        jsonl = os.path.join(out, 'runs.jsonl')
        if rc != 0 or not os.path.exists(jsonl):
            raise ToolError(f'mppi-fit exited {rc} (see {out}/mppi_fit.log)')
        with open(jsonl) as f:
            run = json.loads(f.readline())
        if run.get('error'):
            raise ToolError(f'case {label}: {run["error"]}')
        return {k: run[k] for k in EVIDENCE_FIGURES}


class FitCommand:
    """Any mppi-fit command with a run folder: settings {'command': 'diagnose' (words of the
    subcommand), 'result': 'report.json' (a JSON or YAML file it writes in --out DIR: diagnose's
    report.json, calibrate's calibrated.yaml), and its flags
    without dashes}. The figures: the result's top-level numbers, strings and booleans, as result.KEY."""
    kind = 'fit_command'

    def __init__(self, out_root, bin_dir=None):
        self.out_root = os.path.abspath(out_root)
        self.binary = paths.program('mppi-fit', bin_dir)

    def __call__(self, settings):
        from .keys import task_key
        settings = dict(settings)
        try:
            command_words, result = settings.pop('command').split(), settings.pop('result')
        except KeyError as e:
            raise ToolError(f'fit_command task: setting {e} is required') from None
        out = os.path.join(self.out_root, task_key(self.kind, {**settings, 'command': command_words}))
        os.makedirs(out, exist_ok=True)
        command = [self.binary, *command_words, *runfile.settings_to_flags(settings), '--out', out]
        with open(os.path.join(out, 'mppi_fit.log'), 'w') as log:
            log.write(' '.join(command) + '\n')
            log.flush()
            rc = subprocess.call(command, cwd=paths.REPO_ROOT, stdout=log, stderr=subprocess.STDOUT)
        path = os.path.join(out, result)
        if rc != 0 or not os.path.exists(path):
            raise ToolError(f'mppi-fit {" ".join(command_words)} exited {rc} without {result} (see {out}/mppi_fit.log)')
        with open(path) as f:
            data = json.load(f) if path.endswith('.json') else yaml.safe_load(f)
        if not isinstance(data, dict):
            raise ToolError(f'{path}: expected a JSON or YAML mapping')
        # prefixed: a result repeats some of the settings (the log, the holdout)
        return {f'result.{k}': v for k, v in data.items() if isinstance(v, (int, float, str, bool))}


def make_adapter(kind, out_root, bin_dir=None):
    """The adapter of a task kind; ToolError for an unknown kind."""
    if kind == 'closed_loop':
        return ClosedLoop()
    if kind == 'sim_process':
        return SimProcess(os.path.join(out_root, 'runs'), bin_dir)
    if kind == 'evidence_case':
        return EvidenceCase(os.path.join(out_root, 'cases'), bin_dir)
    if kind == 'fit_command':
        return FitCommand(os.path.join(out_root, 'fit'), bin_dir)
    raise ToolError(f'task kind {kind!r}: closed_loop, sim_process, evidence_case or fit_command')
