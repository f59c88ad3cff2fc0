"""How fast a BARN episode runs: the Jackal of jackal_gazebo's spawn_jackal.launch with its front
laser (run.py's JACKAL_LASER settings) in a BARN world, with jackal_helper's move_base_DWA.launch
and a goal of (0, 10) in odom (tests/data/ros1/tryout/jackal_barn.launch). "build" runs 0.1
simulated seconds: the wall time of a whole process start, launch reading, world and diagram
build; "episode" runs --duration simulated seconds and reports the real-time factors by the wall
clock and by CPU time (the run is single-threaded: the CPU figure is the one-core figure), of the
whole process, and "run CPU rtf", the running phase alone (the build run's CPU time subtracted):
the figure the >= 4x target is about.

    .venv/bin/python bench/jackal_barn_rtf.py [--duration 20] [--world 0] [--before DIR] [--repeat N]

--before DIR also runs every case with the package's source taken from DIR (as husky_rtf.py;
the result's command names it BEFORE/src).
--repeat N runs each case N times, the versions taking turns, and keeps the run with the least
CPU time (the least disturbed by other work on a shared machine; CPU time on a loaded machine
still varies by 10-20% from run to run).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from _result import BenchResult
from husky_rtf import BUILD_S, run_case, run_cpu_rtf

LASER = {"JACKAL_LASER": "1", "JACKAL_LASER_MODEL": "ust10", "JACKAL_LASER_OFFSET": "-0.065 0 0.01"}
TARGETS = {"run": ">= 4", "build": "<= 5"}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--world", type=int, default=0, help="a vendored BARN world's index")
    parser.add_argument("--before", type=Path, help="an earlier checkout's src/ to compare with")
    parser.add_argument("--repeat", type=int, default=1, help="runs of each case; the least CPU is kept")
    opts = parser.parse_args()
    out = BenchResult(
        "jackal_barn_rtf",
        "a BARN episode (Jackal with its laser, move_base DWA): build wall time, real-time factor "
        "by the wall clock and by CPU time",
    )
    if opts.before:  # the page names no machine's paths
        out.command = out.command.replace(str(opts.before), "BEFORE/src")
    versions = [("after", None)] + ([("before", opts.before.resolve())] if opts.before else [])
    args = (f"world_idx:={opts.world}",)
    runs: dict[tuple[str, str], list[dict]] = {}
    for _ in range(opts.repeat):
        for label, src in versions:
            for case, duration in (("build", BUILD_S), ("episode", opts.duration)):
                result = run_case("jackal_barn.launch", LASER, duration, src, args)
                print(f"{case} ({label}): {result}", flush=True)
                runs.setdefault((case, label), []).append(result)
    for label, _ in versions:
        suffix = f" ({label})" if opts.before else ""
        build, episode = (_least_disturbed(runs[(case, label)]) for case in ("build", "episode"))
        episode["run_cpu_rtf"] = run_cpu_rtf(build, episode, opts.duration)
        out.add("wall", build["wall_s"], "s", row=f"build{suffix}", target=TARGETS["build"])
        out.add("CPU", build["cpu_s"], "s", row=f"build{suffix}")
        out.add("CPU", episode["cpu_s"], "s", row=f"episode{suffix}")
        for key, column in (("rtf", "rtf"), ("cpu_rtf", "CPU rtf"), ("run_cpu_rtf", "run CPU rtf")):
            if episode.get(key) is not None:
                target = TARGETS["run"] if key == "run_cpu_rtf" and label == "after" else None
                out.add(column, episode[key], "x real time", row=f"episode{suffix}", target=target)
        for name, result in ((f"build{suffix}", build), (f"episode{suffix}", episode)):
            if "error" in result:
                out.add("error", result["error"], row=name)
            out.records[name] = dict(result, runs=runs[(name.split(" ")[0], label)])
    out.write()
    return 0


def _least_disturbed(results: list[dict]) -> dict:
    """The run with the least CPU time among those without an error (else the first)."""
    ok = [r for r in results if "error" not in r]
    return min(ok, key=lambda r: r["cpu_s"]) if ok else results[0]


if __name__ == "__main__":
    sys.exit(main())
