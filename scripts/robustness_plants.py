#!/usr/bin/env python3
"""Writes the mismatch plants of the robustness benchmark (docs/ROBUSTNESS.md) to
data/config/robustness/: each a corrected-model file (dynamics/corrected_model.hpp) whose
nominal is the default single-track plant, data/config/autorally_single_track.yaml, copied
as it is, with exactly one effect (dynamics/effects.hpp) set.

    /usr/bin/python3 scripts/robustness_plants.py [--root DIR]

Python 3 standard library only.
"""
import argparse
import os

NOMINAL = 'data/config/autorally_single_track.yaml'
OUT_DIR = 'data/config/robustness'

# name -> (effect ids, effect values, description lines)
PLANTS = {
    'delay': (['steer_delay', 'throttle_delay'],
              {'steer_delay_s': 0.08, 'throttle_delay_s': 0.08},
              ['a pure 0.08-s delay of both commands (4 control steps at 50 Hz).',
               'Written as the effects steer_delay_s / throttle_delay_s: mppi-sim moves a corrected',
               "plant's pure delays onto the plant's actuators (ActuatorLimits::*_delay_s, exact",
               'transport delays at the 500-Hz plant step; sim/closed_loop.cpp), which mppi-sim has',
               'no flag for, so the file is the whole plant and the variants keep their own flags.']),
    'grip': (['friction_change'],
             {'grip_change_time_s': 0.0, 'grip_scale': 0.7},
             ['grip -30 %: the whole friction curve x 0.7 (Pacejka D and Sv x 0.7, B and C kept)',
              'from t = 0 on. friction_change scales the whole curve; tire_saturation would keep',
              'Sv and would scale only the peak.']),
    'grade': (['road_grade'],
              {'grade_x': 0.06, 'grade_y': 0.0},
              ['a 6 % grade: the ground is the plane z = 0.06 x (world x), so on a loop the car',
               'climbs on one side and descends on the other (-m g grad z along the body axes).']),
    'payload': (['payload'],
                {'mass_scale': 1.25, 'yaw_inertia_scale': 1.25},
                ['mass +25 % (payload), yaw inertia x 1.25 as well: a load spread like the car',
                 "itself (same radius of gyration). The tyres' loads follow the mass; the motor and",
                 'the tyre coefficients are the nominal ones.']),
}


def nominal_params_block(root):
    """The nominal single-track file's keys, comments dropped, indented under nominal_params."""
    lines = []
    with open(os.path.join(root, NOMINAL)) as f:
        for raw in f:
            text = raw.split('#', 1)[0].rstrip()
            if text.strip():
                lines.append('  ' + text)
    return 'nominal_params:\n' + '\n'.join(lines) + '\n'


def plant_text(name, root):
    ids, values, description = PLANTS[name]
    header = [f'Robustness benchmark plant "{name}" (docs/ROBUSTNESS.md): the default single-track plant',
              f'({NOMINAL}) with one mismatch:'] + ['  ' + d for d in description] + [
              'Made by scripts/robustness_plants.py (regenerate with /usr/bin/python3',
              'scripts/robustness_plants.py); a corrected-model file (dynamics/corrected_model.hpp).',
              f'Use: mppi-sim --plant corrected --plant-params {OUT_DIR}/{name}.yaml']
    body = ['model: corrected', 'nominal: single-track', 'selected: [' + ', '.join(ids) + ']', 'effects:']
    body += [f'  {key}: {value}' for key, value in values.items()]
    return '\n'.join('# ' + h for h in header) + '\n' + '\n'.join(body) + '\n' + nominal_params_block(root)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--root', default=os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
    args = parser.parse_args()
    os.makedirs(os.path.join(args.root, OUT_DIR), exist_ok=True)
    for name in PLANTS:
        path = os.path.join(args.root, OUT_DIR, name + '.yaml')
        with open(path, 'w') as f:
            f.write(plant_text(name, args.root))
        print('wrote', os.path.relpath(path, args.root))


if __name__ == '__main__':
    main()
