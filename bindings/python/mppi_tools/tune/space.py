"""What mppi-tune may tune: each parameter, its range and the mppi-sim setting it sets.

Names are those of `mppi-tune --params`; a range is overridden with --range NAME=LO:HI (numbers)
or NAME=a|b|c (choices)."""
from dataclasses import dataclass, field

from ..errors import ToolError


@dataclass
class Param:
    name: str
    setting: str          # run-file key (mppi-sim flag without dashes) or cost.NAME
    kind: str             # float | int | choice
    low: float = 0.0
    high: float = 0.0
    log: bool = False
    choices: list = field(default_factory=list)
    default: object = None  # mppi-sim's default (the baseline trial)
    needs: tuple = ()       # (other parameter, value): only tuned when that one has that value
    what: str = ''

    def suggest(self, trial):
        if self.kind == 'choice':
            return trial.suggest_categorical(self.name, self.choices)
        if self.kind == 'int':
            return trial.suggest_int(self.name, int(self.low), int(self.high), log=self.log)
        # 4 significant digits: the value written to the run file is the one the trial ran
        return float(f'{trial.suggest_float(self.name, self.low, self.high, log=self.log):.4g}')


PARAMS = [
    Param('lambda', 'lambda', 'float', 0.5, 40.0, log=True, default=6.0, what='MPPI temperature (fixed)'),
    Param('ess-target', 'ess-target', 'float', 0.005, 0.2, log=True, default=None,
          what='adaptive temperature: ESS share of K (replaces lambda when tuned)'),
    Param('noise-steer', 'noise-std[0]', 'float', 0.1, 0.6, default=0.275, what='sampling std, steering'),
    Param('noise-throttle', 'noise-std[1]', 'float', 0.1, 0.6, default=0.3, what='sampling std, throttle'),
    Param('samples', 'samples', 'choice', choices=[512, 1024, 1920, 2560], default=1920, what='K'),
    Param('speed', 'speed', 'float', 6.0, 12.0, default=8.0, what='target speed [m/s] (the cost\'s v_x^d)'),
    Param('track-weight', 'cost.track_weight', 'float', 10.0, 300.0, log=True, default=100.0, what='cost w1'),
    Param('speed-weight', 'cost.speed_weight', 'float', 1.0, 30.0, log=True, default=4.25, what='cost w2'),
    Param('crash-weight', 'cost.crash_weight', 'float', 1000.0, 50000.0, log=True, default=10000.0,
          what='cost w3'),
    Param('slip-weight', 'cost.slip_weight', 'float', 0.1, 20.0, log=True, default=1.75, what='cost w4'),
    Param('smoothing', 'smoothing', 'choice', choices=[0, 5, 9, 15], default=5, what='Savitzky-Golay window'),
    Param('sampler', 'sampler', 'choice', choices=['gaussian', 'lowpass', 'smooth'], default='gaussian',
          what='perturbation sampler'),
    Param('sampler-cutoff', 'sampler-cutoff', 'float', 1.0, 15.0, log=True, default=None,
          needs=('sampler', 'lowpass'), what='lowpass sampler corner frequency [Hz]'),
    Param('smooth-time', 'smooth-time', 'float', 0.1, 2.0, log=True, default=None, needs=('sampler', 'smooth'),
          what='smooth sampler time constant [s]'),
    Param('variant', 'variant', 'choice', choices=['plain', 'tube', 'robust'], default='plain',
          what='controller variant'),
    Param('actuator-model', 'actuator-model', 'choice', choices=['none', 'plant'], default='none',
          what='plan through the actuators'),
]
BY_NAME = {p.name: p for p in PARAMS}
DEFAULT_PARAMS = ['ess-target', 'noise-steer', 'noise-throttle', 'speed', 'track-weight', 'speed-weight',
                  'slip-weight', 'smoothing']


def select(names, ranges=()):
    """The parameters named (in the given order), with --range overrides applied. ToolError for
    an unknown name and for an empty search space (no parameter, or each held to one value)."""
    if not names:
        raise ToolError(f'--params: no parameter to tune (an empty search space); name some of: {", ".join(BY_NAME)}')
    unknown = [n for n in names if n not in BY_NAME]
    if unknown:
        raise ToolError(f'--params: unknown {unknown}; known: {", ".join(BY_NAME)}')
    if 'lambda' in names and 'ess-target' in names:
        raise ToolError('--params: lambda and ess-target exclude each other (the ESS target sets lambda)')
    chosen = {n: Param(**{**BY_NAME[n].__dict__}) for n in names}
    for text in ranges:
        name, sep, value = text.partition('=')
        if not sep or name not in chosen:
            raise ToolError(f'--range {text!r}: expected NAME=LO:HI or NAME=a|b with NAME one of --params '
                            f'({", ".join(chosen)})')
        p = chosen[name]
        try:
            if p.kind == 'choice':
                kind = type(p.choices[0])
                p.choices = [kind(v) for v in value.split('|')]
            else:
                lo, hi = (float(v) for v in value.split(':'))
                if not lo < hi:
                    raise ValueError
                p.low, p.high = lo, hi
        except ValueError:
            raise ToolError(f'--range {text!r}: expected {name}=LO:HI with LO < HI' if p.kind != 'choice'
                            else f'--range {text!r}: expected {name}=a|b|c') from None
    if all(p.kind == 'choice' and len(p.choices) == 1 for p in chosen.values()):
        raise ToolError(f'--params {",".join(chosen)}: each has one value left (--range), an empty search space; '
                        f'set them with --fixed and tune something else')
    for p in chosen.values():
        if p.needs and p.needs[0] not in chosen:
            raise ToolError(f'--params: {p.name} needs {p.needs[0]} tuned too (it applies when {p.needs[0]} = '
                            f'{p.needs[1]})')
    return list(chosen.values())


def check_fixed(params, fixed):
    """ToolError for a --fixed setting that a tuned parameter sets (the trial would overwrite it)."""
    for p in params:
        setting = 'noise-std' if p.setting.startswith('noise-std[') else p.setting
        if setting in fixed:
            raise ToolError(f'--fixed {setting}={fixed[setting]}: --params {p.name} tunes that setting; '
                            f'leave it out of --params (fixed) or out of --fixed (tuned)')


def suggest(trial, params, fixed):
    """The settings of a trial: the fixed settings, then the suggested ones."""
    settings = dict(fixed)
    values = {}
    for p in params:
        if p.needs and values.get(p.needs[0]) != p.needs[1]:
            continue
        values[p.name] = p.suggest(trial)
    apply(settings, params, values)
    return settings, values


def apply(settings, params, values):
    """Sets each parameter's value in settings (noise channels into noise-std)."""
    for p in params:
        if p.name not in values:
            continue
        if p.setting.startswith('noise-std['):
            noise = list(settings.get('noise-std', [0.275, 0.3]))
            noise[int(p.setting[len('noise-std[')])] = values[p.name]
            settings['noise-std'] = noise
        else:
            settings[p.setting] = values[p.name]
    return settings
