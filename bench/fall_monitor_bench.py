"""What the world node's fall monitor costs: the qbot_sim launch's real-time factor without it,
with it at its default 10 Hz, and checking at every plant step (1 kHz).

Each run is a child process (one Drake diagram per process, as the CLI runs them), the three
variants alternated round by round so the machine's drift touches them alike; prints each
round (real-time factor, the process's CPU seconds, and the seconds spent inside the checks
themselves) and the medians' ratios to the run without the monitor, and writes them to
bench/results/. On a shared machine the time inside the checks, against the run's CPU time, is
the steadiest figure.

    .venv/bin/python bench/fall_monitor_bench.py [--duration 10] [--rounds 5]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _result import BenchResult

VARIANTS = {"off": None, "10 Hz": 10.0, "1 kHz": 1000.0}


def child(variant: str, duration: float) -> None:
    from twil_control import PACKAGE_ROOT
    from twil_control.gazebo import server as drake_world
    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import RunOptions, run
    from twil_control.world import fall_monitor

    rate = VARIANTS[variant]
    inside, calls = [0.0], [0]
    if rate is None:  # a monitor that watches nothing: no timer, no checks
        fall_monitor.FallMonitor = type(
            "Off", (), {"__init__": lambda self, sim, distance: None, "watched": []}
        )
    else:
        check = drake_world.DrakeWorld._check_falls

        def timed(self, event):
            start = time.perf_counter()
            check(self, event)
            inside[0] += time.perf_counter() - start
            calls[0] += 1

        drake_world.DrakeWorld._check_falls = timed
    plan = load_launch(PACKAGE_ROOT / "launch/qbot_sim.launch.yaml", {})
    if rate is not None:
        plan.params.set("/gazebo/fall_check_rate", rate)
    cpu = time.process_time()
    with tempfile.TemporaryDirectory() as tmp:
        result = run(plan, RunOptions(duration=duration, bag=Path(tmp) / "bench.bag"))
    cpu = time.process_time() - cpu
    if result.failed:
        raise SystemExit(f"the run failed: {result.error or result.failures}")
    if rate is not None and abs(calls[0] - rate * duration) > 1:
        raise SystemExit(f"{calls[0]} checks at {rate:g} Hz in {duration:g} s: the rate was not applied")
    print(result.realtime_factor, cpu, inside[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="simulated seconds per run")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--child", choices=list(VARIANTS), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child, args.duration)
        return
    result = BenchResult(
        "fall_monitor_bench",
        "the world node's fall monitor: the qbot_sim launch without it, with "
        "it at its default 10 Hz and at every plant step (1 kHz), alternated in child processes",
    )
    runs: dict[str, list[tuple[float, float, float]]] = {v: [] for v in VARIANTS}
    print(f"fall monitor bench: qbot_sim, {args.duration:g} s simulated per run, {args.rounds} rounds")
    for r in range(args.rounds):
        order = list(VARIANTS) if r % 2 == 0 else list(reversed(VARIANTS))
        for variant in order:
            out = subprocess.run(
                [sys.executable, __file__, "--child", variant, "--duration", str(args.duration)],
                check=True,
                capture_output=True,
                text=True,
            ).stdout
            runs[variant].append(tuple(float(v) for v in out.split()[-3:]))
        print(
            f"  round {r + 1}: "
            + ", ".join(
                f"{v} {runs[v][-1][0]:.2f}x (cpu {runs[v][-1][1]:.2f} s, checks "
                f"{1e3 * runs[v][-1][2]:.1f} ms)"
                for v in VARIANTS
            ),
            flush=True,
        )
    base_rtf = statistics.median(r[0] for r in runs["off"])
    base_cpu = statistics.median(r[1] for r in runs["off"])
    for variant, rs in runs.items():
        rtf, cpu = statistics.median(r[0] for r in rs), statistics.median(r[1] for r in rs)
        share = statistics.median(r[2] / r[1] for r in rs)
        print(
            f"  {variant:>5}: real-time factor {rtf:.2f}x (ratio to off {rtf / base_rtf:.3f}), CPU {cpu:.2f} s "
            f"(ratio {cpu / base_cpu:.3f}), inside the checks {100 * share:.2f}% of the CPU time"
        )
        result.add("rtf", rtf, "x real time (median)", row=variant)
        result.add("rtf / off", rtf / base_rtf, row=variant)
        result.add("CPU", cpu, "s (median)", row=variant)
        result.add("CPU / off", cpu / base_cpu, row=variant)
        result.add(
            "inside the checks",
            100 * share,
            "% of the CPU time (median)",
            row=variant,
            headline=variant == "10 Hz" and "fall monitor at 10 Hz: share of the run's CPU",
        )
    result.add("simulated_s", args.duration, "s per run")
    result.add("rounds", args.rounds)
    result.write()


if __name__ == "__main__":
    main()
