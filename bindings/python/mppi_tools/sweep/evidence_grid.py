"""The evidence grid (mppi-fit diagnose sweep --generator independent) as Dask tasks: one task per
case of the grid; the cases' runs.jsonl lines are then joined and summarised by mppi-fit itself
(--summarize), so the table is the one a serial sweep writes."""
import os
import subprocess

from .. import paths, runfile
from ..errors import ToolError


def grid_flags(reduced=False, **options):
    """The mppi-fit flags that pick the grid (the same for listing and for every case)."""
    flags = ['--reduced'] if reduced else []
    return flags + runfile.settings_to_flags({k: v for k, v in options.items() if v is not None})


def list_cases(flags, bin_dir=None):
    """The grid's case labels, in mppi-fit's order."""
    binary = paths.program('mppi-fit', bin_dir)
    done = subprocess.run([binary, 'diagnose', 'sweep', '--generator', 'independent', *flags, '--list-cases'],
                          cwd=paths.REPO_ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        raise ToolError(f'mppi-fit diagnose sweep --list-cases failed ({done.returncode}): {done.stderr.strip()}')
    return [line.strip() for line in done.stdout.splitlines() if line.strip()]


def tasks_for(labels, reduced=False, **options):
    """One task per case label; the grid's options are settings of every task."""
    base = {'reduced': True} if reduced else {}
    base.update({k: v for k, v in options.items() if v is not None})
    return [{'case': label, **base} for label in labels]


def summarize(out_dir, labels, bin_dir=None):
    """Joins the cases' runs.jsonl (in grid order) into out_dir/runs.jsonl and has mppi-fit write
    evidence_sweep.md / .json from it; returns the Markdown path."""
    with open(os.path.join(out_dir, 'runs.jsonl'), 'w') as joined:
        for label in labels:
            path = os.path.join(out_dir, 'cases', label, 'runs.jsonl')
            if os.path.exists(path):
                with open(path) as f:
                    joined.write(f.read())
    binary = paths.program('mppi-fit', bin_dir)
    done = subprocess.run([binary, 'diagnose', 'sweep', '--generator', 'independent', '--summarize', out_dir],
                          cwd=paths.REPO_ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        raise ToolError(f'mppi-fit diagnose sweep --summarize {out_dir} failed: {done.stderr.strip()}')
    return os.path.join(out_dir, 'evidence_sweep.md')
