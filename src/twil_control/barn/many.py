"""Many BARN trials (test.sh's loop: ``--worlds 0:300:6 --runs 10``) on Dask, through the
sweep's machinery: each trial is ``python -m twil_control.barn --world_idx N`` in a process of
its own on a worker (a local cluster of one single-threaded worker per core, or the cluster of
``--scheduler``), recorded as DIR/runs/run_wNNN_rKK.json (status, error, wall and CPU time)
with its log and its out line beside it. A rerun skips recorded trials (failed ones too, unless
``--retry-failed``). At the end ``--out`` is written with every finished trial's line, in world
and run order, and the averages report_test.py prints are printed.
"""

from __future__ import annotations

import json
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from .trial import BarnError, jackal_helper, world

MODULE = "twil_control.barn"


def parse_worlds(text: str) -> list[int]:
    """'START:STOP[:STEP]' (Python's range) or a comma list of indices."""
    try:
        if ":" in text:
            parts = [int(p) for p in text.split(":")]
            if len(parts) not in (2, 3) or (len(parts) == 3 and parts[2] <= 0):
                raise ValueError
            indices = list(range(*parts))
        else:
            indices = [int(p) for p in text.split(",") if p.strip()]
    except ValueError:
        raise BarnError(f"--worlds {text!r}: use START:STOP[:STEP] (e.g. 0:300:6) or a list 0,6,12") from None
    indices = list(dict.fromkeys(indices))  # a world named twice runs --runs times, not twice that
    if not indices:
        raise BarnError(f"--worlds {text!r} names no world")
    for idx in indices:
        world(idx)  # an index that does not exist: BarnError
    return indices


def run_id(idx: int, run: int) -> str:
    return f"w{idx:03d}_r{run:02d}"


def run_many(opts) -> int:
    from ..sweep.execute import execute_tasks
    from ..sweep.progress import progress_wanted
    from ..sweep.worker import FAILED, OK, RunTask, read_record

    indices = parse_worlds(opts.worlds)
    if opts.runs < 1:
        raise BarnError(f"--runs must be >= 1 (got {opts.runs})")
    if opts.workers is not None and (opts.workers < 1 or opts.scheduler):
        raise BarnError(
            "--workers N (N >= 1) sizes the local cluster; with --scheduler the cluster's workers run"
        )
    jackal_helper()  # the catkin src must be there before anything starts
    nav = str(opts.nav_launch.absolute()) if opts.nav_launch else ""
    if nav and not Path(nav).is_file():
        raise BarnError(f"--nav_launch {opts.nav_launch}: no such file")
    out = opts.out.absolute()
    directory = (opts.dir or out.with_name(out.name + ".d")).absolute()
    runs_dir = directory / "runs"
    runs_dir.mkdir(parents=True, exist_ok=True)
    _check_same_stack(directory / "barn.json", nav, opts.time_step)

    tasks, records, order = [], {}, []
    for idx in indices:
        for k in range(opts.runs):
            rid = run_id(idx, k)
            order.append(rid)
            record = read_record(runs_dir / f"run_{rid}.json")
            if record is not None and (record.get("status") == OK or not opts.retry_failed):
                records[rid] = record
                continue
            line_file = runs_dir / f"run_{rid}.txt"
            line_file.unlink(missing_ok=True)
            argv = ["--world_idx", str(idx), "--out", str(line_file), "--time_limit", repr(opts.time_limit)]
            argv += ["--stats", str(runs_dir / f"run_{rid}.stats.json"), "--seed", str(k)]
            argv += ["--nav_launch", nav] if nav else []
            argv += ["--time_step", repr(opts.time_step)] if opts.time_step is not None else []
            tasks.append(
                RunTask(
                    run_id=rid,
                    index=len(order) - 1,
                    launch="",
                    argv=argv,
                    run_dir=str(runs_dir),
                    timeout=opts.timeout,
                    module=MODULE,
                    record_bag=False,
                )
            )
    echo = _echo
    echo(
        f"BARN: {len(order)} trials ({len(indices)} worlds x {opts.runs}), {len(order) - len(tasks)} already "
        f"recorded, {len(tasks)} to run; records in {runs_dir}"
    )
    wall0 = time.monotonic()
    interrupted = False
    if tasks:
        interrupted = execute_tasks(tasks, opts.scheduler, opts.workers, len(order), progress_wanted(), echo)
    wall = time.monotonic() - wall0
    lines, failed, cpu = [], [], 0.0
    for rid in order:
        record = read_record(runs_dir / f"run_{rid}.json")
        if record is None:
            continue
        cpu += record.get("cpu_time") or 0.0
        line_file = runs_dir / f"run_{rid}.txt"
        if record.get("status") == OK and line_file.is_file():
            lines.append(line_file.read_text())
        else:
            failed.append((rid, record.get("error") or record.get("status") or FAILED))
    out.write_text("".join(lines))
    echo(
        f"{len(lines)} trial lines in {out}; {len(failed)} failed, {len(order) - len(lines) - len(failed)} not run"
    )
    for rid, error in failed[:10]:
        echo(f"  failed {rid}: {error} (log {runs_dir / f'run_{rid}.log'})")
    if lines:
        print(summary(lines))
    echo(
        f"wall time {wall:.1f} s for {len(tasks)} trials run now; CPU time of all recorded trials {cpu:.1f} s"
    )
    if interrupted:
        return 130
    return 1 if failed else 0


def summary(lines: list[str]) -> str:
    """report_test.py's averages over worlds of the per-world means (the metric as recorded)."""
    by_world = defaultdict(list)
    for line in lines:
        f = line.split()
        by_world[int(f[0])].append((int(f[1]), int(f[2]), int(f[3]), float(f[4]), float(f[5])))
    times = [np.mean([r[3] for r in rows if r[0]]) for rows in by_world.values() if any(r[0] for r in rows)]

    def mean(i):
        return np.mean([np.mean([r[i] for r in rows]) for rows in by_world.values()])

    avg_time = np.mean(times) if times else float("nan")
    return (
        f"Avg Time: {avg_time:.4f}, Avg Metric: {mean(4):.4f}, Avg Success: {mean(0):.4f}, "
        f"Avg Collision: {mean(1):.4f}, Avg Timeout: {mean(2):.4f}"
    )


WORLD_STEP = "unset (the world's <max_step_size>)"


def _check_same_stack(path: Path, nav: str, time_step: float | None = None) -> None:
    """A records folder belongs to one navigation stack and one plant step: another one needs
    another --dir."""
    if path.is_file():
        earlier = json.loads(path.read_text())
        if earlier.get("nav_launch", "") != nav:
            raise BarnError(
                f"{path.parent} holds trials of --nav_launch "
                f"{earlier.get('nav_launch') or '(jackal_helper move_base_DWA)'}; "
                f"give another --dir for {nav or 'the default stack'}"
            )
        if earlier.get("time_step") != time_step:
            before, now = (
                WORLD_STEP if s is None else f"{s:g} s" for s in (earlier.get("time_step"), time_step)
            )
            raise BarnError(
                f"{path.parent} holds trials at --time_step {before}; give another --dir for --time_step {now}"
            )
        return
    path.write_text(json.dumps({"nav_launch": nav, "time_step": time_step}))


def _echo(text: str) -> None:
    print(text, file=sys.stderr, flush=True)
