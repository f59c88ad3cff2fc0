"""How fast a BARN episode runs: the Jackal of jackal_gazebo's spawn_jackal.launch with its front
laser (run.py's JACKAL_LASER settings) in a BARN world, with jackal_helper's move_base_DWA.launch
and a goal of (0, 10) in odom (tests/data/ros1/tryout/jackal_barn.launch). "build" runs 0.1
simulated seconds: the wall time of a whole process start, launch reading, world and diagram
build; "episode" runs --duration simulated seconds and reports the real-time factors by the wall
clock and by CPU time (the run is single-threaded: the CPU figure is the one-core figure), of the
whole process, and "run CPU rtf", the running phase alone (the build run's CPU time subtracted):
the figure the >= 4x target is about.

    .venv/bin/python bench/jackal_barn_rtf.py [--duration 20] [--world 0] [--before DIR]

--before DIR also runs every case with the package's source taken from DIR (as husky_rtf.py).
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
    opts = parser.parse_args()
    out = BenchResult(
        "jackal_barn_rtf",
        "a BARN episode (Jackal with its laser, move_base DWA): build wall time, real-time factor "
        "by the wall clock and by CPU time",
    )
    versions = [("after", None)] + ([("before", opts.before.resolve())] if opts.before else [])
    args = (f"world_idx:={opts.world}",)
    for label, src in versions:
        suffix = f" ({label})" if opts.before else ""
        build = run_case("jackal_barn.launch", LASER, BUILD_S, src, args)
        print(f"build{suffix}: {build}", flush=True)
        out.add("wall", build["wall_s"], "s", row=f"build{suffix}", target=TARGETS["build"])
        episode = run_case("jackal_barn.launch", LASER, opts.duration, src, args)
        print(f"episode{suffix}: {episode}", flush=True)
        episode["run_cpu_rtf"] = run_cpu_rtf(build, episode, opts.duration)
        for key, column in (("rtf", "rtf"), ("cpu_rtf", "CPU rtf"), ("run_cpu_rtf", "run CPU rtf")):
            if episode.get(key) is not None:
                target = TARGETS["run"] if key == "run_cpu_rtf" and label == "after" else None
                out.add(column, episode[key], "x real time", row=f"episode{suffix}", target=target)
        for name, result in ((f"build{suffix}", build), (f"episode{suffix}", episode)):
            if "error" in result:
                out.add("error", result["error"], row=name)
            out.records[name] = result
    out.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
