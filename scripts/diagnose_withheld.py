#!/usr/bin/env python3
"""The diagnosis on effects it cannot name: each single-effect recording of an evidence sweep is
diagnosed again with the ids that would name its hidden effect taken out of the candidates, so the
effect is outside the library. An honest answer is then "nothing named" or an unexplained mismatch
(report.json `unexplained`); a name outside the effect's actuator family is a wrong physical name.

Usage:
  scripts/diagnose_withheld.py SWEEP_DIR EFFECT[,EFFECT...] [--mppi-fit build/bin/mppi-fit]
      [--params data/config/autorally_single_track.yaml] [--out out/withheld]
SWEEP_DIR: the --out of `mppi-fit diagnose sweep --generator independent` (runs.jsonl and the
recordings); EFFECT: the sweep's case names (steer_backlash, gyro_bias, payload, ...).
Prints one JSON line per run and the totals; writes them to OUT/withheld.jsonl.
"""
import argparse
import json
import os
import subprocess
import sys

# The actuator families (EffectSpec::dynamics_of): naming another form of one actuator's dynamics
# is not a wrong physical name.
FAMILY = {'steer_delay': 'steer', 'steer_lag': 'steer', 'steer_rate_limit': 'steer', 'steer_backlash': 'steer',
          'throttle_delay': 'throttle', 'throttle_lag': 'throttle', 'throttle_rate_limit': 'throttle'}


def default_candidates(mppi_fit):
    """The default candidate ids, from `mppi-fit diagnose --help` ("Effect ids: ..."; those marked
    "(by name only)" are not default candidates)."""
    text = subprocess.run([mppi_fit, 'diagnose', '--help'], capture_output=True, text=True, check=True).stdout
    line = next(l for l in text.splitlines() if l.startswith('Effect ids:'))
    words = line[len('Effect ids:'):].replace('(by name only)', '#').split()
    ids = []
    for w in words:
        if w == '#':
            ids.pop()
        else:
            ids.append(w)
    return ids


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('sweep_dir')
    ap.add_argument('effects')
    ap.add_argument('--mppi-fit', default='build/bin/mppi-fit')
    ap.add_argument('--params', default='data/config/autorally_single_track.yaml')
    ap.add_argument('--out', default='out/withheld')
    a = ap.parse_args()
    candidates = default_candidates(a.mppi_fit)
    cases = set(a.effects.split(','))
    os.makedirs(a.out, exist_ok=True)
    runs = [json.loads(l) for l in open(os.path.join(a.sweep_dir, 'runs.jsonl'))]
    results = []
    with open(os.path.join(a.out, 'withheld.jsonl'), 'w') as log:
        for r in runs:
            if len(r['effects']) != 1 or r['effects'][0] not in cases:
                continue
            withheld = set(r['acceptable_ids'])
            out_dir = os.path.join(a.out, r['label'])
            subprocess.run([a.mppi_fit, 'diagnose', '--log', os.path.join(a.sweep_dir, r['label'] + '.csv'),
                            '--params', a.params, '--no-plots', '--quiet', '--out', out_dir,
                            '--effects', ','.join(c for c in candidates if c not in withheld)],
                           check=True, capture_output=True)
            report = json.load(open(os.path.join(out_dir, 'report.json')))
            families = {FAMILY[w] for w in withheld if w in FAMILY}
            named = report['selected']
            wrong = [n for n in named if FAMILY.get(n) not in families]
            res = {'label': r['label'], 'withheld': sorted(withheld), 'named': named,
                   'unexplained': len(report.get('unexplained', [])), 'wrong_physical_names': wrong}
            print(json.dumps(res))
            sys.stdout.flush()
            log.write(json.dumps(res) + '\n')
            results.append(res)
    n = len(results)
    no_wrong = sum(1 for x in results if not x['wrong_physical_names'])
    said_unexplained = sum(1 for x in results if x['unexplained'] > 0)
    print(f'runs {n}: no wrong physical name (nothing, its actuator family, or an unexplained mismatch) '
          f'{no_wrong}; a wrong physical name {n - no_wrong}; an unexplained mismatch reported {said_unexplained}')

if __name__ == '__main__':
    main()
