"""Parameter importances without scikit-learn (which Optuna's fANOVA needs): for each parameter,
the share of the objective's variance over the feasible trials that its value alone explains
(the correlation ratio eta^2 over quantile bins of a number, or over the choices of a choice).
A screening measure, as fANOVA's first-order terms are; the shares need not add up to 1."""
import math


def _bins(values, count):
    """Bin index of each value: quantile bins of numbers, one bin per distinct choice."""
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values) and len(set(values)) > count:
        ordered = sorted(values)
        edges = [ordered[int(len(ordered) * k / count)] for k in range(1, count)]
        return [sum(v >= e for e in edges) for v in values]
    kinds = sorted(set(map(str, values)))
    return [kinds.index(str(v)) for v in values]


def importances(trials, bins=4):
    """{parameter: eta^2} over trials [(params dict, value)], largest first."""
    if len(trials) < 3:
        return {}
    values = [v for _, v in trials]
    mean = sum(values) / len(values)
    total = sum((v - mean) ** 2 for v in values)
    names = sorted({n for params, _ in trials for n in params})
    out = {}
    for name in names:
        present = [(p[name], v) for p, v in trials if name in p]
        if len(present) < 3 or total <= 0:
            continue
        groups = {}
        for b, (_, v) in zip(_bins([x for x, _ in present], bins), present):
            groups.setdefault(b, []).append(v)
        between = sum(len(g) * (sum(g) / len(g) - mean) ** 2 for g in groups.values())
        out[name] = between / total if math.isfinite(between) else 0.0
    return dict(sorted(out.items(), key=lambda kv: -kv[1]))
