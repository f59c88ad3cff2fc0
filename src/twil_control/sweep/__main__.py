"""``python -m twil_control.sweep SWEEP.yaml [--scheduler ADDRESS] [--workers N] [--out DIR]``

Runs every run of a sweep file (one launch each, in its own process, on Dask workers), then
writes OUT/results.csv and OUT/results.parquet, one plot per metric in OUT/plots/, and prints
a summary. Exit codes: 0 when every run is ok, 1 when some run failed or timed out (the table
has its error), 2 for a bad sweep file or option (nothing ran), 130 after Ctrl-C (the table
holds what finished; a rerun does the rest).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import exit_on_error
from .spec import SweepError, load_sweep


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m twil_control.sweep",
        description="Run a launch file many times with varied args (grid, list or random "
        "samples) on a local Dask cluster or an existing one; one bag and one "
        "row of metrics per run.",
    )
    p.add_argument("sweep", type=Path, help="sweep file (YAML), e.g. config/sweeps/cart_gains.yaml")
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="Dask scheduler address (tcp://host:port) or scheduler file; its "
        "workers need this checkout and --out at the same paths",
    )
    p.add_argument(
        "--workers", type=int, metavar="N", help="local cluster size (default: the machine's cores)"
    )
    p.add_argument(
        "--out", type=Path, metavar="DIR", help="output directory (default: runs/sweeps/<sweep name>)"
    )
    p.add_argument(
        "--retry-failed",
        action="store_true",
        help="run failed and timed-out runs again (default: keep their records)",
    )
    p.add_argument("--list", action="store_true", help="print the runs and exit")
    return p


def main(argv: list[str] | None = None) -> int:
    opts = _parser().parse_args(argv)
    return exit_on_error(lambda: _main(opts))


def _main(opts: argparse.Namespace) -> int:
    if opts.workers is not None and opts.workers < 1:
        raise SweepError(f"--workers must be >= 1 (got {opts.workers})")
    if opts.workers is not None and opts.scheduler:
        raise SweepError(
            "--workers sizes the local cluster; with --scheduler the cluster's own workers run the sweep"
        )
    sweep = load_sweep(opts.sweep)
    out = opts.out or Path("runs") / "sweeps" / sweep.name
    if opts.list:
        return _list(sweep)
    if out.exists() and not out.is_dir():
        raise SweepError(f"--out {out} is a file; name a folder for the sweep's runs and table")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise SweepError(f"--out {out}: cannot make the folder ({error.strerror})") from None

    from .execute import run_sweep

    outcome = run_sweep(
        sweep, out, scheduler=opts.scheduler, workers=opts.workers, retry_failed=opts.retry_failed
    )
    print(outcome.summary)
    print(
        f"table: {outcome.csv} and {outcome.parquet.name}; plots: "
        f"{len(outcome.plots)} in {outcome.csv.parent / 'plots'}"
    )
    if outcome.interrupted:
        return 130
    return 0 if outcome.all_ok else 1


def _list(sweep) -> int:
    from .runs import runs_of

    runs, duplicates = runs_of(sweep)
    for run in runs:
        print(f"{run.index:4d} {run.run_id} " + " ".join(run.launch_argv()))
    print(f"{len(runs)} runs" + (f" ({duplicates} duplicates merged)" if duplicates else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
