"""``python -m twil_control.barn``: the-barn-challenge's run.py, here.

One trial: ``--world_idx N [--gui] [--out out.txt]`` prints run.py's lines and appends its
out.txt line (BARN's report_test.py reads the file). Many: ``--worlds START:STOP:STEP --runs R``
runs every trial in a process of its own on Dask (a local cluster, or ``--scheduler ADDR``),
records each, skips those already recorded on a rerun, and writes their lines to ``--out``.
Exit codes: 0 done, 1 a trial failed, 2 bad input (nothing ran), 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

WALL0 = time.perf_counter()  # the process's start, near enough: before the heavy imports

from .trial import BarnError


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m twil_control.barn",
        description="The BARN navigation benchmark as the-barn-challenge's run.py runs it: the Jackal "
        "in a BARN world, move_base to the far side, success, collision or timeout and the metric.",
    )
    p.add_argument("--world_idx", type=int, default=0, help="world: BARN 0-299, DynaBARN 300-359 (0)")
    p.add_argument("--gui", action="store_true", help="watch it in the browser view, in real time")
    p.add_argument("--out", type=Path, default=Path("out.txt"), help="file the result line is appended to")
    p.add_argument(
        "--nav_launch",
        type=Path,
        metavar="FILE",
        help="your navigation stack's launch file (default: jackal_helper's move_base_DWA.launch)",
    )
    p.add_argument(
        "--time_limit", type=float, default=100.0, metavar="S", help="seconds a trial may take (run.py: 100)"
    )
    p.add_argument(
        "--time_step",
        type=float,
        metavar="S",
        help="the plant's step in seconds, up to 0.01 (default: the world's <max_step_size>, BARN's 0.001): "
        "a longer step runs faster and is less faithful (docs/barn.md)",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seeds every random source (the sensors' noise); many trials: the run index",
    )
    p.add_argument("--bag", type=Path, metavar="PATH", help="record the trial into this bag")
    p.add_argument(
        "--stats",
        type=Path,
        metavar="JSON",
        help="write the trial's timings here (start-up and build, simulated and wall time, CPU)",
    )
    p.add_argument("--quiet", action="store_true", help="errors only, no running time line")
    p.add_argument("--verbose", action="store_true", help="every node's log line")
    many = p.add_argument_group("many trials (test.sh's loop) on Dask")
    many.add_argument("--worlds", metavar="START:STOP[:STEP]", help="world indices, e.g. 0:300:6 (test set)")
    many.add_argument("--runs", type=int, default=1, help="trials per world (test.sh: 10)")
    many.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address or scheduler file")
    many.add_argument("--workers", type=int, metavar="N", help="local cluster size (default: the cores)")
    many.add_argument(
        "--dir", type=Path, metavar="DIR", help="where each trial's record and log go (default: OUT.d)"
    )
    many.add_argument("--retry-failed", action="store_true", help="run failed trials again")
    many.add_argument(
        "--timeout", type=float, default=1800.0, help="wall seconds a trial may take (1800: a loaded machine)"
    )
    return p


def main(argv: list[str] | None = None) -> int:
    opts = _parser().parse_args(argv)
    if opts.worlds is not None:
        from .many import run_many

        try:
            return run_many(opts)
        except BarnError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
    from ..launch.logging_setup import configure_logging

    stamp = configure_logging(debug=False, quiet=not opts.verbose)
    import logging

    if opts.quiet:
        logging.getLogger().setLevel(logging.ERROR)
    elif opts.gui:  # the view's address, an INFO line, is what --gui is for
        logging.getLogger("twil_control.view").setLevel(logging.INFO)
    from .trial import run_trial

    try:
        outcome = run_trial(
            opts.world_idx,
            opts.out,
            gui=opts.gui,
            nav_launch=opts.nav_launch,
            bag=opts.bag,
            time_limit=opts.time_limit,
            time_step=opts.time_step,
            seed=opts.seed,
            show_time=not opts.quiet and sys.stdout.isatty(),
            log_stamp=stamp,
        )
    except BarnError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2 if "did not finish" not in str(error) else 1
    except (ValueError, OSError, LookupError) as error:  # the launch's own input errors
        print(f"error: {error}", file=sys.stderr)
        return 2
    if opts.stats is not None:
        _write_stats(opts.stats, outcome)
    return 0


def _write_stats(path: Path, outcome) -> None:
    import json
    import resource
    import time

    children = resource.getrusage(resource.RUSAGE_CHILDREN)  # xacro, run as a limited subprocess
    stats = {
        "world_idx": outcome.world.idx,
        "status": outcome.status,
        "trial_time": outcome.time,
        "process_wall": time.perf_counter() - WALL0,
        "process_cpu": time.process_time(),
        "children_cpu": children.ru_utime + children.ru_stime,
        "build_wall": outcome.build_wall,
        "startup_wall": outcome.started_at - WALL0,  # process start (imports included) to time 0
        "sim_time": outcome.sim_time,
        "run_wall": outcome.run_wall,
        "run_cpu": outcome.run_cpu,
    }
    path.write_text(json.dumps(stats, indent=1))


if __name__ == "__main__":
    sys.exit(main())
