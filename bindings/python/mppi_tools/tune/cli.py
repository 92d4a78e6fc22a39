"""mppi-tune: tunes the controller's settings with Optuna, trials as closed-loop runs on Dask.

    mppi-tune run [--params ess-target,noise-steer,...] [--trials 40] [--tracks gazebo,marietta]
                  [--seeds 1,2] [--laps 2] [--fixed model=single-track ...] [--storage URL]
                  [--workers N | --scheduler tcp://HOST:8786 | --serial] [--out DIR] [--run-file FILE]
    mppi-tune report --storage URL --study NAME [--out DIR] [--run-file FILE]
    mppi-tune evaluate --run-file FILE [--baseline "--model single-track ..."] [--tracks gazebo,ccrf]
                       [--seeds 11,12,13] [--laps 5] [--out DIR]
    mppi-tune params    (what can be tuned, with ranges)

The objective: mean lap time over the limit lap over every (track, seed), 0 crashes / stalls
required (else infeasible). docs/TUNING.md."""
import argparse
import os
import shlex
import sys

from .. import runfile
from ..errors import ToolError
from ..sweep.cli import add_cluster_options, client_for
from ..sweep.cluster import close_client
from . import evaluate, objective, report, space, study

MATCHED = {'model': 'single-track', 'plant': 'single-track'}


def csv_list(text, kind=str):
    try:
        return [kind(v) for v in text.split(',') if v]
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r}: expected a comma-separated list') from None


def fixed_settings(pairs):
    settings = dict(MATCHED)
    for text in pairs:
        key, sep, value = text.partition('=')
        if not sep or not key:
            raise ToolError(f'--fixed {text!r}: expected KEY=VALUE (an mppi-sim run-file key, or cost.NAME)')
        settings[key] = yaml_scalar(value)
    runfile.split_cost(settings)  # unknown cost keys fail here
    return settings


def yaml_scalar(text):
    import yaml
    return yaml.safe_load(text) if text else ''


def cmd_run(args):
    params = space.select(args.params, args.range)
    fixed = fixed_settings(args.fixed)
    space.check_fixed(params, fixed)
    evaluation = objective.Evaluation(args.tracks, args.seeds, args.laps)
    os.makedirs(args.out, exist_ok=True)
    url = args.storage or f'sqlite:///{os.path.abspath(os.path.join(args.out, "study.db"))}'
    st = study.create(url, args.study, args.sampler_seed)
    if args.serial:  # parallel workers would race for a queued trial (Optuna hands it to each that asks)
        study.enqueue_defaults(st, params)
    already = len(st.trials)
    print(f'[tune] study {args.study} in {url}: {already} trials before, {args.trials} to run; '
          f'{len(params)} parameters ({", ".join(p.name for p in params)}); each trial {len(evaluation.runs({}))} runs '
          f'({",".join(evaluation.tracks)} x seeds {",".join(map(str, evaluation.seeds))}, {evaluation.laps} laps)',
          flush=True)
    client = client_for(args)
    try:
        if client is None:
            for n in range(args.trials):
                r = study.run_trial(url, args.study, params, fixed, evaluation, args.sampler_seed + already + n)
                print(f'[tune] {r}', flush=True)
        else:
            from distributed import as_completed, progress
            import threading
            futures = [client.submit(study.run_trial, url, args.study, params, fixed, evaluation,
                                     args.sampler_seed + already + n, pure=False, key=f'trial-{already + n}')
                       for n in range(args.trials)]
            bar = threading.Thread(target=progress, args=(futures,), kwargs={'notebook': False, 'interval': '2s'},
                                   daemon=True)
            bar.start()
            for future in as_completed(futures):
                print(f'\n[tune] {future.result()}', flush=True)
            bar.join(timeout=10)  # the bar ends with its futures; closing the client under it would cancel it
    finally:
        if client is not None:
            close_client(client)
    return finish(st, args, url)


def finish(st, args, url):
    records, imp = report.write_all(st, args.out, args.bin)
    run_file = args.run_file or os.path.join(args.out, 'best.yaml')
    header = (f'mppi-sim settings tuned by mppi-tune (study {st.study_name}, {len(records)} trials, storage {url}).'
              if url.startswith('sqlite') else f'mppi-sim settings tuned by mppi-tune (study {st.study_name}).')
    best = report.write_run_file(st, run_file, header)
    print(f'-> {args.out}/trials.csv, history.png, importance.png; importances: '
          + ', '.join(f'{k} {v:.2f}' for k, v in imp.items()))
    if best is None:
        print('no feasible trial (every one crashed, stalled or did not finish): no run file written')
        return 1
    print(f'-> {run_file}: trial {best["number"]}, mean lap / limit lap {best["value"]:.4f}')
    return 0


def cmd_report(args):
    import optuna
    st = optuna.load_study(study_name=args.study, storage=study.storage_for(args.storage))
    return finish(st, args, args.storage)


def cmd_evaluate(args):
    if not os.path.exists(args.run_file):
        raise ToolError(f'--run-file {args.run_file}: no such file')
    baseline = runfile.flags_to_settings(shlex.split(args.baseline))
    client = client_for(args)
    try:
        frame, failures = evaluate.evaluate(args.run_file, baseline, args.tracks, args.seeds, args.laps, args.out,
                                            client, args.bin)
    finally:
        if client is not None:
            close_client(client)
    if failures:
        print(f'{len(failures)} runs failed; rerun to retry them', file=sys.stderr)
        return 1
    md = evaluate.comparison(frame, args.tracks, args.run_file, args.baseline)
    path = os.path.join(args.out, 'heldout.md')
    with open(path, 'w') as f:
        f.write(f'# Held-out evaluation ({args.laps} laps per run)\n\n'
                f'Generated by `mppi-tune evaluate`; do not edit by hand.\n\n' + md)
    print(md + f'-> {path}, {os.path.join(args.out, "heldout.csv")}')
    return 0


def cmd_params(_args):
    for p in space.PARAMS:
        rng = '|'.join(map(str, p.choices)) if p.kind == 'choice' else f'{p.low:g}:{p.high:g}{" log" if p.log else ""}'
        print(f'{p.name:16s} {p.setting:20s} {rng:28s} default {p.default}  {p.what}')
    print(f'default --params: {",".join(space.DEFAULT_PARAMS)}')
    return 0


def main(argv=None):
    parser = argparse.ArgumentParser(prog='mppi-tune', description=__doc__.split('\n\n')[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    sub = parser.add_subparsers(dest='command', required=True)
    run = sub.add_parser('run', help='run trials')
    run.add_argument('--params', type=csv_list, default=space.DEFAULT_PARAMS, help='what to tune (mppi-tune params)')
    run.add_argument('--range', action='append', default=[], help='NAME=LO:HI or NAME=a|b|c (repeatable)')
    run.add_argument('--fixed', action='append', default=[],
                     help='KEY=VALUE: a setting of every run (run-file key or cost.NAME; default model and plant '
                          'single-track)')
    run.add_argument('--trials', type=int, default=40)
    run.add_argument('--tracks', type=csv_list, default=['gazebo', 'marietta'])
    run.add_argument('--seeds', type=lambda t: csv_list(t, int), default=[1, 2])
    run.add_argument('--laps', type=int, default=2)
    run.add_argument('--sampler-seed', type=int, default=1, help="the Optuna sampler's seed")
    rep = sub.add_parser('report', help='the figures and run file of a study')
    for p in (run, rep):
        p.add_argument('--storage', help='SQLAlchemy URL (default sqlite:///OUT/study.db; PostgreSQL for a cluster)')
        p.add_argument('--study', default='mppi', help='study name')
        p.add_argument('--out', default='out/tune', help='trials.csv, history.png, importance.png, best.yaml')
        p.add_argument('--run-file', help='where the best settings go (default OUT/best.yaml)')
    ev = sub.add_parser('evaluate', help='a run file against the baseline on held-out seeds and tracks')
    ev.add_argument('--run-file', required=True)
    ev.add_argument('--baseline', default='--model single-track --plant single-track --speed 8',
                    help='mppi-sim flags of the baseline (default: the robustness benchmark\'s matched plain row)')
    ev.add_argument('--tracks', type=csv_list, default=['gazebo', 'ccrf'])
    ev.add_argument('--seeds', type=lambda t: csv_list(t, int), default=[11, 12, 13])
    ev.add_argument('--laps', type=int, default=5)
    ev.add_argument('--out', default='out/tune/heldout')
    for p in (run, rep, ev):
        p.add_argument('--bin', help='folder of mppi-sim / mppi-plot (default: build/bin)')
    for p in (run, ev):
        add_cluster_options(p)
    sub.add_parser('params', help='what can be tuned')
    args = parser.parse_args(argv)
    if args.command == 'report' and not args.storage:
        parser.error('report needs --storage')
    try:
        return {'run': cmd_run, 'report': cmd_report, 'evaluate': cmd_evaluate, 'params': cmd_params}[args.command](args)
    except ToolError as e:
        print(f'mppi-tune: error: {e}', file=sys.stderr)
        return 2


if __name__ == '__main__':
    sys.exit(main())
