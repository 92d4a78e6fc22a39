"""mppi-sweep: sweeps of closed-loop runs, diagnoses and evidence recordings on Dask.

    mppi-sweep grid FILE.yaml [--out DIR] [--workers N | --scheduler tcp://HOST:8786 | --serial]
    mppi-sweep evidence [--reduced] [--cases A,B | --first N] [--duration S] [--out DIR] [...]

Results: DIR/sweep.csv, one row per task (key = hash of its settings; a rerun skips the rows
there). The robustness benchmark runs on Dask with scripts/robustness_benchmark.py --dask.
docs/TUNING.md."""
import argparse
import os
import sys

from ..errors import ToolError
from . import evidence_grid
from .adapters import make_adapter
from .cluster import close_client, open_client
from .grid_file import read_grid_file
from .runner import run_sweep


def add_cluster_options(parser):
    where = parser.add_mutually_exclusive_group()
    where.add_argument('--scheduler', metavar='ADDRESS',
                       help='a running Dask scheduler (dask-scheduler prints tcp://HOST:8786); default: a LocalCluster')
    where.add_argument('--serial', action='store_true', help='no Dask: the tasks one after another in this process')
    parser.add_argument('--workers', type=int, default=2, help='LocalCluster worker processes (1 thread each)')


def client_for(args):
    return None if args.serial else open_client(args.scheduler, args.workers)


def cmd_grid(args):
    kind, tasks = read_grid_file(args.file)
    adapter = make_adapter(kind, args.out, args.bin)
    return execute(args, adapter, tasks)


def execute(args, adapter, tasks):
    client = client_for(args)
    try:
        table, failures = run_sweep(adapter, tasks, args.table or os.path.join(args.out, 'sweep.csv'), client)
    finally:
        if client is not None:
            close_client(client)
    print(f'-> {table.path} ({len(table.rows)} rows)')
    return 1 if failures else 0


def cmd_evidence(args):
    options = {'seeds': args.seeds, 'duration': args.duration, 'rate': args.rate, 'vehicle': args.vehicle}
    flags = evidence_grid.grid_flags(args.reduced, **options)
    labels = evidence_grid.list_cases(flags, args.bin)
    if args.cases:
        wanted = args.cases.split(',')
        unknown = [c for c in wanted if c not in labels]
        if unknown:
            raise ToolError(f'--cases: {unknown} are not cases of this grid ({len(labels)} cases: '
                            f'mppi-fit diagnose sweep --generator independent --list-cases)')
        labels = wanted
    if args.first:
        labels = labels[:args.first]
    adapter = make_adapter('evidence_case', args.out, args.bin)
    rc = execute(args, adapter, evidence_grid.tasks_for(labels, args.reduced, **options))
    md = evidence_grid.summarize(args.out, labels, args.bin)
    print(f'-> {md}')
    return rc


def main(argv=None):
    parser = argparse.ArgumentParser(prog='mppi-sweep', description=__doc__.split('\n\n')[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    sub = parser.add_subparsers(dest='command', required=True)
    grid = sub.add_parser('grid', help='the tasks of a grid file (kind, base, grid, tasks)')
    grid.add_argument('file')
    evidence = sub.add_parser('evidence', help='the evidence grid of mppi-fit diagnose sweep --generator independent')
    evidence.add_argument('--reduced', action='store_true', help='the reduced grid (1 seed, 3 pairs, 4 effect-free)')
    evidence.add_argument('--seeds', type=int, help='seeds per effect and size')
    evidence.add_argument('--duration', type=float, help='recording length [s]')
    evidence.add_argument('--rate', type=float, help="the driver's and the log's rate [Hz]")
    evidence.add_argument('--vehicle', help="the car's constants (YAML)")
    evidence.add_argument('--cases', help='only these case labels (comma-separated)')
    evidence.add_argument('--first', type=int, help='only the first N cases of the grid')
    for p in (grid, evidence):
        p.add_argument('--out', default='out/sweep', help='run folders and sweep.csv')
        p.add_argument('--table', help='the result table (.csv, or .parquet with pyarrow; default OUT/sweep.csv)')
        p.add_argument('--bin', help='folder of mppi-sim / mppi-fit (default: build/bin)')
        add_cluster_options(p)
    args = parser.parse_args(argv)
    try:
        return cmd_grid(args) if args.command == 'grid' else cmd_evidence(args)
    except ToolError as e:
        print(f'mppi-sweep: error: {e}', file=sys.stderr)
        return 2


if __name__ == '__main__':
    sys.exit(main())
