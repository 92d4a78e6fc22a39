"""The tuner's objective: the settings drive every (track, seed) of the evaluation; the score is
the mean lap time over the limit lap (docs/LIMIT_LAP.md, so tracks of different lengths weigh the
same), and a run with a crash, a stall or unfinished laps makes the settings infeasible."""
import math
from dataclasses import dataclass, field

# Infeasible settings score this plus one per incident: worse than any clean lap (>= 1 by physics).
INFEASIBLE = 10.0


@dataclass
class Evaluation:
    tracks: list = field(default_factory=lambda: ['gazebo', 'marietta'])
    seeds: list = field(default_factory=lambda: [1, 2])
    laps: int = 2

    def runs(self, settings):
        """The settings of each closed-loop run (1 thread each: the result does not depend on scheduling)."""
        return [{**settings, 'track': t, 'seed': s, 'laps': self.laps, 'threads': 1}
                for t in self.tracks for s in self.seeds]


def score(figures):
    """(value, feasible, incidents) of the runs' figures."""
    incidents = sum(f['crashes'] + f['stalls'] + (0 if f['finished'] else 1) for f in figures)
    ratios = [f['mean_lap_over_limit'] for f in figures]
    if incidents or not all(r is not None and math.isfinite(r) for r in ratios):
        return INFEASIBLE + incidents, False, incidents
    return sum(ratios) / len(ratios), True, 0
