"""Speed-up of a sweep on a local Dask cluster: the same 8 short runs with 1 and with 2 workers.

Both sweeps run in one invocation, one after the other, into fresh output directories (so
nothing is resumed), and are timed end to end: cluster start, every run (a launch subprocess
each: interpreter and Drake start-up, simulation, bag), metrics, table and plots, cluster
close. Prints both wall times, the mean run wall time inside each sweep, and the speed-up.

    .venv/bin/python bench/sweep_bench.py [--runs 8] [--duration 1.0]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from _common import BenchResult

from twil_control.sweep import load_sweep, run_sweep


def _sweep_file(directory: Path, runs: int, duration: float) -> Path:
    # distinct runs (their identities differ by seed), each the WAM under computed torque
    path = directory / "bench.yaml"
    path.write_text(
        f"launch: launch/wam_computed_torque.launch.yaml\n"
        f"duration: {duration}\ntimeout: 600\n"
        f"grid: {{seed: {{range: [0, {runs}]}}}}\n"
        f"plots: [computed_torque.rms_deviation_all_joints_rad]\n"
    )
    return path


def _timed(sweep_path: Path, out: Path, workers: int) -> tuple[float, float]:
    start = time.perf_counter()
    outcome = run_sweep(load_sweep(sweep_path), out, workers=workers, progress=False, echo=lambda text: None)
    wall = time.perf_counter() - start
    if not outcome.all_ok:
        raise SystemExit(f"a run failed:\n{outcome.summary}")
    return wall, float(outcome.frame["wall_time"].mean())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=8)
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds per run")
    args = parser.parse_args()
    result = BenchResult(
        "sweep_bench",
        "a sweep of short WAM launches on a local Dask cluster: the same runs with 1 "
        "and with 2 workers, end to end",
    )
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sweep = _sweep_file(tmp, args.runs, args.duration)
        one, one_run = _timed(sweep, tmp / "w1", 1)
        two, two_run = _timed(sweep, tmp / "w2", 2)
    print(
        f"sweep bench: {args.runs} runs of wam_computed_torque, {args.duration:g} s simulated "
        f"each ({os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f})"
    )
    print(f"  1 worker : {one:6.1f} s wall (a run: {one_run:5.2f} s)")
    print(f"  2 workers: {two:6.1f} s wall (a run: {two_run:5.2f} s)")
    print(f"  speed-up 2 workers / 1 worker: {one / two:5.2f}")
    result.add("runs", args.runs)
    result.add("one_worker_s", one, "s wall")
    result.add("two_workers_s", two, "s wall")
    result.add("run_alone_s", one_run, "s per run, 1 worker")
    result.add("run_two_at_a_time_s", two_run, "s per run, 2 workers")
    result.add("speedup", one / two, "2 workers / 1 worker", headline="sweep speed-up, 2 workers / 1")
    result.write()


if __name__ == "__main__":
    main()
