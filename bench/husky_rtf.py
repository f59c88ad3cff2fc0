"""How fast the Husky runs from its own launch files: husky_gazebo's spawn_husky.launch (EKF,
twist_mux, teleop) driving a square, the same with its LMS1xx laser, and with the laser and
husky_navigation's gmapping_demo.launch (gmapping's 200 m x 200 m map, move_base) on three
house goals (tests/data/ros1/tryout). Each case runs as its own process for --duration simulated
seconds; it reports the wall-clock real-time factor and the CPU one (simulated seconds per
CPU second: what the wall figure is on an idle machine, the run being single-threaded), both of
the whole process, start-up included; and "run CPU rtf", the running phase alone: a run of
BUILD_S simulated seconds (the process's start, launch reading and build) is subtracted.

    .venv/bin/python bench/husky_rtf.py [--duration 20] [--before DIR]

--before DIR also runs every case with the package's source taken from DIR (an earlier
commit's src/ in its whole tree, whose package.xml $(find twil_control) needs: `git archive
COMMIT | tar -x -C /tmp/before`, then --before /tmp/before/src), in the same run, for a
before/after comparison on one machine state. Run each version once first: numba compiles a
fresh tree's kernels on its first run, which would count as that version's start-up.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _result import ROOT, BenchResult

TRYOUT = ROOT / "tests" / "data" / "ros1" / "tryout"
ROS1 = ROOT / "tests" / "data" / "ros1"
#: simulated seconds of the run that measures a case's start-up and build
BUILD_S = 0.1
#: the running phase's targets (issue 32: the Husky with its laser at >= 2x real time)
RUN_TARGETS = {"square_lms1xx": ">= 2"}
CASES = {
    "square": ("husky_control.launch", {}),
    "square_lms1xx": ("husky_control.launch", {"HUSKY_LMS1XX_ENABLED": "1"}),
    "navigation_lms1xx": ("husky_nav.launch", {"HUSKY_LMS1XX_ENABLED": "1"}),
}


def run_case(
    launch: str, env_extra: dict, duration: float, src: Path | None, args: tuple[str, ...] = ()
) -> dict:
    """Run one tryout launch (with launch `args`) for `duration` simulated seconds; wall and CPU."""
    env = dict(os.environ, ROS_PACKAGE_PATH=f"{ROS1 / 'vendor'}:{ROS1 / 'stubs'}", **env_extra)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    with tempfile.TemporaryDirectory() as tmp:
        command = [sys.executable, "-m", "twil_control.launch", str(TRYOUT / launch), *args]
        command += ["--duration", str(duration), "--bag", str(Path(tmp) / "run.bag")]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        done = subprocess.run(command, env=env, capture_output=True, text=True, cwd=ROOT)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    # to 10 ms: the running phase is a difference of two CPU times of a few seconds each
    result = {"wall_s": round(wall, 2), "cpu_s": round(cpu, 2)}
    if done.returncode != 0:
        result["error"] = (done.stderr.strip().splitlines() or ["no output"])[-1]
        return result
    result["rtf"] = duration / wall
    result["cpu_rtf"] = duration / cpu
    return result


def run_cpu_rtf(build: dict, episode: dict, duration: float) -> float | None:
    """Simulated seconds per CPU second of the running phase: an episode's CPU time less the
    start-up and build's (a run of BUILD_S simulated seconds); None if either failed."""
    if "error" in build or "error" in episode or episode["cpu_s"] <= build["cpu_s"]:
        return None
    return (duration - BUILD_S) / (episode["cpu_s"] - build["cpu_s"])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--before", type=Path, help="an earlier checkout's src/ to compare with")
    parser.add_argument("--cases", default=",".join(CASES), help=f"of: {', '.join(CASES)}")
    opts = parser.parse_args()
    out = BenchResult(
        "husky_rtf",
        "the Husky from its own launch files (square; with its LMS1xx; with gmapping_demo.launch): "
        "real-time factor by the wall clock and by CPU time",
    )
    versions = [("after", None)] + ([("before", opts.before.resolve())] if opts.before else [])
    for case in [c.strip() for c in opts.cases.split(",")]:
        launch, env_extra = CASES[case]
        for label, src in versions:
            row = f"{case} ({label})" if opts.before else case
            build = run_case(launch, env_extra, BUILD_S, src)
            result = run_case(launch, env_extra, opts.duration, src)
            result["run_cpu_rtf"] = run_cpu_rtf(build, result, opts.duration)
            result["build_cpu_s"] = build["cpu_s"]
            print(f"{row}: {result}", flush=True)
            for key, column, unit in (("rtf", "rtf", "x real time"), ("cpu_rtf", "CPU rtf", "x real time")):
                if key in result:
                    out.add(column, result[key], unit, row=row)
            if result["run_cpu_rtf"] is not None:
                target = RUN_TARGETS.get(case) if label == "after" else None
                out.add("run CPU rtf", result["run_cpu_rtf"], "x real time", row=row, target=target)
            if "error" in result:
                out.add("error", result["error"], row=row)
            out.records[row] = result
    out.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
