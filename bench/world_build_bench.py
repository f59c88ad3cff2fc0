"""How long a large world takes to load, and how much memory: grids of static boxes.

Each case runs in a child process of its own (its peak memory is the child's maximum resident
set size), on worlds of N static 0.5 x 0.6 x 1 m boxes (a collision and a visual each) on a
floor:
- ``build N``: what a launch does with a world: Simulation.add_world, the qbot spawned, the
  plant finalized, the diagram built and its context made;
- ``read N``: the world's fixed shapes read alone (world_shapes: what the map rasteriser cuts);
- ``launch N``: the qbot_sim launch in that world, the time to build it (its first laser
  scan, which cuts the whole world, included) and the real-time factor (and CPU seconds per
  simulated second) of its first 2 simulated seconds (N = 0: the default world), to see what
  else grows with the world once it is loaded (the laser's scene, SceneGraph's queries).
Figures: ``time``/``CPU`` the case's own work (wall and CPU seconds), ``peak memory`` the
child's; the whole child's wall and CPU seconds (imports included) are kept in the result's
records. Targets: a 1,000-box world builds in under 5 s; 20,000 in under 60 s and 2 GB. Wall
time on a shared machine varies with other jobs; CPU time (user + system) is the steadier
figure. A case still running after --timeout seconds is stopped and reported as such. Beyond 2,000
collision geometries (max_collision_geometries) the static ones collide only near the robots
(world/proximity_window.py), so the 1,990-box world is the largest with every collision in
SceneGraph's pair table and the 20,000-box one is windowed; beyond 500 static visuals a world's
boxes are drawn as merged meshes (world/merged_visuals.py), as in every world here.
The 20,000-box cases take minutes: they run with --large. One Gazebo-saved world is built as
it comes, with no edits: BARN's world_0 (tests/data/ros1/vendor/jackal_helper: a ground plane
first, about 200 cylinder models, a <state> block; normalised by description.gazebo_world),
target under 5 s.

    .venv/bin/python bench/world_build_bench.py [--large] [--timeout 600]
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from _result import BenchResult

ROOT = Path(__file__).resolve().parents[1]
#: worlds users bring, built as they are: row label -> file
FILES = {"BARN world_0": ROOT / "tests/data/ros1/vendor/jackal_helper/worlds/BARN/world_0.world"}


def box_world(n: int) -> str:
    """An SDF world: a floor and `n` static boxes on a grid 2 m apart, the origin kept free."""
    side = max(1, math.ceil(math.sqrt(n)))
    half = side + 5.0
    parts = [
        '<?xml version="1.0"?>\n<sdf version="1.9">\n<world name="boxes">',
        f'<model name="floor"><static>true</static><link name="floor_link">'
        f"<pose>0 0 -0.05 0 0 0</pose>"
        f'<collision name="collision"><geometry><box><size>{4 * half} {4 * half} 0.1</size>'
        f'</box></geometry></collision><visual name="visual"><geometry><box>'
        f"<size>{4 * half} {4 * half} 0.1</size></box></geometry></visual></link></model>",
    ]
    for i in range(n):
        x, y = 3.0 + 2.0 * (i % side), 3.0 + 2.0 * (i // side)
        geometry = "<geometry><box><size>0.5 0.6 1</size></box></geometry>"
        parts.append(
            f'<model name="box_{i}"><static>true</static><pose>{x} {y} 0.5 0 0 0.1</pose>'
            f'<link name="link"><collision name="collision">{geometry}</collision>'
            f'<visual name="visual">{geometry}<material><diffuse>0.8 0.5 0.2 1</diffuse>'
            f"</material></visual></link></model>"
        )
    parts.append("</world>\n</sdf>\n")
    return "\n".join(parts)


#: Each case prints "<name> <number>" lines; step_s and step_cpu_s time the case's own work
#: (the imports before it excluded).
CODE = {
    "build": """
        import time
        from twil_control.world.simulation import Simulation
        t0, c0 = time.perf_counter(), time.process_time()
        sim = Simulation()
        sim.add_world(WORLD)
        sim.spawn("qbot", "qbot")
        sim.finalize()
        sim.build().Initialize()
        print("step_s", time.perf_counter() - t0)
        print("step_cpu_s", time.process_time() - c0)
    """,
    "read": """
        import time
        from twil_control.world.world_section import world_section
        t0, c0 = time.perf_counter(), time.process_time()
        print("shapes", len(world_section(WORLD, 0.135)))
        print("step_s", time.perf_counter() - t0)
        print("step_cpu_s", time.process_time() - c0)
    """,
    "launch": """
        import time
        from twil_control import PACKAGE_ROOT
        from twil_control.launch.loader import load_launch
        from twil_control.launch.runner import Launch
        args = {"world": WORLD} if WORLD else {}
        launch = Launch(load_launch(PACKAGE_ROOT / "launch/qbot_sim.launch.yaml", args))
        t0, c0 = time.perf_counter(), time.process_time()
        launch.build()
        launch.start()
        t1, c1 = time.perf_counter(), time.process_time()
        launch.simulator.AdvanceTo(2.0)
        t2, c2 = time.perf_counter(), time.process_time()
        launch.shutdown()
        print("step_s", t1 - t0)
        print("step_cpu_s", c1 - c0)
        print("rtf", 2.0 / (t2 - t1))
        print("cpu_per_sim_s", (c2 - c1) / 2.0)
    """,
}


#: Put before every case: the child reports its own CPU time and peak memory as it exits,
#: also after an error (a world refused).
REPORT = """
import atexit, resource
def _report():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    print("cpu_s", usage.ru_utime + usage.ru_stime)
    print("peak_rss_mb", usage.ru_maxrss / 1024)
atexit.register(_report)
"""


def _proc_usage(pid: int) -> dict:
    """CPU seconds and peak memory of a running process, from /proc (before it is stopped)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return {}
    hwm = next(int(line.split()[1]) for line in status.splitlines() if line.startswith("VmHWM"))
    ticks = os.sysconf("SC_CLK_TCK")
    return {
        "cpu_s": round((int(fields[11]) + int(fields[12])) / ticks, 2),
        "peak_rss_mb": round(hwm / 1024, 1),
    }


def measure(case: str, world: str, timeout: float) -> dict:
    """Run one case in a child: wall and CPU seconds, peak memory, and what it printed."""
    code = REPORT + f"WORLD = {world!r}\n" + textwrap.dedent(CODE[case])
    start = time.perf_counter()
    child = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    result: dict = {}
    try:
        out, err = child.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        result = {"timed_out": True, **_proc_usage(child.pid)}
        child.kill()
        out, err = child.communicate()
    result["wall_s"] = round(time.perf_counter() - start, 2)
    if child.returncode != 0 and not result.get("timed_out"):
        result["error"] = (err.strip().splitlines() or [f"exit {child.returncode}"])[-1][:300]
    for line in out.splitlines():
        key, _, value = line.partition(" ")
        result[key] = round(float(value), 2)
    return result


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--large", action="store_true", help="also the 20,000-box world (minutes)")
    p.add_argument("--timeout", type=float, default=600.0, help="seconds a case may take (600)")
    args = p.parse_args()
    out = BenchResult(
        "world_build_bench",
        "worlds of N static boxes: what a launch does to load one (build), "
        "its shapes read alone for the map (read), and the qbot_sim launch in it (launch): time, "
        "CPU, peak memory, real-time factor",
    )
    cases = [("build", 1000), ("build", 1990), ("read", 1000), ("launch", 0), ("launch", 1000)]
    if args.large:
        cases[1:1] = [("build", 20000)]
        cases[4:4] = [("read", 20000)]
        cases.append(("launch", 20000))
    cases.insert(2, ("build", "BARN world_0"))
    with tempfile.TemporaryDirectory() as tmp:
        for case, n in cases:
            world = ""
            if isinstance(n, str):
                world = str(FILES[n])
            elif n:
                world = str(Path(tmp) / f"boxes_{n}.sdf")
                if not os.path.exists(world):
                    Path(world).write_text(box_world(n))
            result = measure(case, world, args.timeout)
            what = n if isinstance(n, str) else f"{n:6d} boxes"
            print(f"{case:6s} {what}: " + ", ".join(f"{k} {v}" for k, v in result.items()), flush=True)
            record(out, case, n, result)
    out.write()
    return 0


TARGETS = {
    (1000, "time"): "< 5",
    (20000, "time"): "< 60",
    (20000, "peak memory"): "< 2000",
    ("BARN world_0", "time"): "< 5",
}


def record(out: BenchResult, case: str, n: int, result: dict) -> None:
    """One case as a row of the table (its targets, for builds, even when it failed)."""
    row = (
        f"{case}, {n}" if isinstance(n, str) else (f"{case}, {n:,} boxes" if n else f"{case}, default world")
    )
    failed = "error" in result or result.get("timed_out")
    for column, key, unit in (
        ("time", "step_s", "s"),
        ("CPU", "step_cpu_s", "s"),
        ("peak memory", "peak_rss_mb", "MB"),
        ("rtf", "rtf", "x real time"),
        ("CPU per simulated s", "cpu_per_sim_s", "s"),
        ("shapes", "shapes", ""),
    ):
        target = TARGETS.get((n, column)) if case == "build" else None
        if key in result or target:
            # a refused or stopped build meets no target, whatever it used before it stopped
            value = None if failed and target else result.get(key)
            out.add(
                column,
                value,
                unit,
                row=row,
                target=target,
                headline=bool(target)
                and (f"{n} build: {column}" if isinstance(n, str) else f"{n:,}-box world build: {column}"),
            )
    if failed:
        out.add("error", result.get("error") or f"stopped after {result['wall_s']:g} s", row=row)
    out.records[row] = {k: result[k] for k in ("wall_s", "cpu_s") if k in result}


if __name__ == "__main__":
    sys.exit(main())
