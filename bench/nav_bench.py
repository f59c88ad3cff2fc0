"""Navigation benchmark, one run: OMPL planners on the house world's map (sim/worlds/house.sdf
rasterised at 0.05 m by twil_control.tools.rasterize), against the grid A* optimum; grid A*
time; TrajectoryPlanner time per control cycle; the navigation launch's real-time factor beside
qbot_sim's (the same robot, world and laser without navigation), wall and CPU time.

    .venv/bin/python bench/nav_bench.py [--pairs 10] [--budget 1.0] [--seed 0] [--launch-duration 20] [--launch-rounds 3] [--local-only]

Start/goal pairs are seeded random free cells the grid connects. The costmap is the package's
configuration (config/costmap_common_params.yaml: inflation_radius 0.55, cost_scaling_factor 10,
the wheel-inclusive footprint).
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from _common import BenchResult, host_steal_seconds

from twil_control import PACKAGE_ROOT
from twil_control.mapping.map_io import read_map
from twil_control.navigation import costmap as cm
from twil_control.navigation import grid_planner as gp
from twil_control.navigation import local_planner as lp
from twil_control.navigation import ompl_planner as op
from twil_control.navigation.footprint import FootprintCells, parse_footprint
from twil_control.tools import rasterize

PLANNERS = ("RRTConnect", "RRTstar", "InformedRRTstar", "BITstar", "PRMstar")


def house_costmap():
    common = yaml.safe_load((PACKAGE_ROOT / "config/costmap_common_params.yaml").read_text())
    fp = parse_footprint(common["footprint"], common.get("footprint_padding", 0.0))
    with tempfile.TemporaryDirectory() as tmp:
        rasterize.main([str(PACKAGE_ROOT / "sim/worlds/house.sdf"), "-o", str(Path(tmp) / "house")])
        occ = read_map(Path(tmp) / "house.yaml")
    cells = FootprintCells(fp, occ.resolution)
    m = cm.Costmap(occ.data.shape[1], occ.data.shape[0], occ.resolution, occ.origin[0], occ.origin[1])
    m.costs = cm.inflate(
        cm.occupancy_to_cost(occ.data, track_unknown=False),
        occ.resolution,
        cells.inscribed,
        common["cost_scaling_factor"],
        common["inflation_radius"],
    )
    return m, cells, common


def pairs(m: cm.Costmap, cells: FootprintCells, n: int, rng) -> list:
    from twil_control.navigation.collision import GridChecker

    checker = GridChecker(m, cells)
    free = np.argwhere(m.costs == 0)
    out = []
    while len(out) < n:
        a, b = free[rng.integers(len(free), size=2)]
        xa, ya = m.cell_to_world(*a)
        xb, yb = m.cell_to_world(*b)
        if math.hypot(xb - xa, yb - ya) < 3.0 or not (
            checker.pose_free(xa, ya, 0.0) and checker.pose_free(xb, yb, 0.0)
        ):
            continue
        try:
            _, cost = gp.plan_cells(m.costs, tuple(a), tuple(b), cost_factor=0.0)
        except gp.NoPathError:
            continue
        out.append(
            (
                (float(xa), float(ya), 0.0),
                (float(xb), float(yb), 0.0),
                tuple(a),
                tuple(b),
                cost * m.resolution,
            )
        )
    return out


def pct(values, q):
    return float(np.percentile(values, q)) if len(values) else math.nan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=10)
    ap.add_argument("--budget", type=float, default=1.0, help="planning_time of the optimising runs (s)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--launch-duration", type=float, default=20.0, help="simulated s of each launch run")
    ap.add_argument("--launch-rounds", type=int, default=3, help="rounds of the launch runs (medians)")
    ap.add_argument("--local-only", action="store_true", help="only the local planner's cycle time")
    args = ap.parse_args()
    result = BenchResult(
        "nav_bench",
        "navigation on the house map: grid A*, the OMPL planners' first solution and "
        "their path after the time budget against the grid optimum, the local planner's cycle, "
        "and the navigation launch's real-time factor beside qbot_sim's",
    )
    m, cells, common = house_costmap()
    rng = np.random.default_rng(args.seed)
    problems = pairs(m, cells, args.pairs, rng)
    gp.plan_cells(m.costs, problems[0][2], problems[0][3])  # JIT warm-up
    op.plan(m, cells, problems[0][0], problems[0][1], op.OmplSettings(planning_time=0.5))
    print(
        f"house.sdf map: {m.shape[1]} x {m.shape[0]} cells at {m.resolution} m; {len(problems)} start/goal pairs "
        f"(seed {args.seed}), straight-line distance median "
        f"{np.median([math.dist(p[0][:2], p[1][:2]) for p in problems]):.2f} m, grid optimum median "
        f"{np.median([p[4] for p in problems]):.2f} m"
    )

    if args.local_only:
        local_planner_cycles(m, cells, problems, result)
        result.write()
        return
    times = {f: [] for f in (0.0, 3.0)}
    for _, _, a, b, _ in problems:
        for f in times:
            t = time.perf_counter()
            gp.plan_cells(m.costs, a, b, cost_factor=f)
            times[f].append(time.perf_counter() - t)
    for f, ts in times.items():
        print(
            f"grid A* (cost_factor {f}): median {1e3 * np.median(ts):.1f} ms, p95 {1e3 * pct(ts, 95):.1f} ms"
        )
        row = f"grid A*, cost_factor {f:g}"
        result.add(
            "solution median",
            1e3 * np.median(ts),
            "ms",
            row=row,
            headline=f == 3.0 and "house plan, grid A* (cost_factor 3), median",
        )
        result.add("solution p95", 1e3 * pct(ts, 95), "ms", row=row)

    print(
        f"\n{'planner':16s} {'first solution: found':>22s} {'median ms':>10s} {'p95 ms':>8s}   "
        f"after {args.budget:.1f} s: length / grid optimum (median, max; objective length)"
    )
    for name in PLANNERS:
        first, ratios, found = [], [], 0
        objective = "length" if name == "PRMstar" else "length_and_cost"
        for start, goal, _, _, optimum in problems:
            r = op.plan(
                m,
                cells,
                start,
                goal,
                op.OmplSettings(
                    planner=name, objective=objective, planning_time=5.0, stop_at_first_solution=True
                ),
                seed=args.seed + 1,
            )
            if r.poses is not None:
                found += 1
                first.append(r.solve_time)
            if name == "RRTConnect":
                ratios.append(r.length / optimum)
                continue
            r = op.plan(
                m,
                cells,
                start,
                goal,
                op.OmplSettings(planner=name, objective="length", planning_time=args.budget),
                seed=args.seed + 1,
            )
            ratios.append(r.length / optimum)
        note = " (RRTConnect does not optimise: its first path)" if name == "RRTConnect" else ""
        print(
            f"{name:16s} {found:>14d}/{len(problems):<7d} {1e3 * np.median(first):10.1f} {1e3 * pct(first, 95):8.1f}"
            f"   {np.median(ratios):.3f}, {np.max(ratios):.3f}{note}"
        )
        result.add("solution median", 1e3 * np.median(first), "ms", row=name)
        result.add("solution p95", 1e3 * pct(first, 95), "ms", row=name)
        result.add(
            "length / optimum",
            np.median(ratios),
            "median" + (", first path" if note else f", after {args.budget:g} s"),
            row=name,
        )

    local_planner_cycles(m, cells, problems, result)
    launches(args.launch_duration, args.launch_rounds, result)
    result.write()


def local_planner_cycles(m: cm.Costmap, cells: FootprintCells, problems: list, result) -> None:
    # local planner: one cycle per pose along grid paths, on a 6 m rolling window of the map; every
    # cycle scores the sampled trajectories (rotate_to_heading_threshold 0: no cheap in-place turns).
    # In move_base the local costmap updates at 5 Hz and the controller runs at 20 Hz, so the
    # collision checker (a distance transform of the window) is rebuilt on one cycle in four:
    # each pose is timed on a new window (rebuilt) and again on the same one (reused).
    tp = yaml.safe_load((PACKAGE_ROOT / "config/base_local_planner_params.yaml").read_text())[
        "TrajectoryPlannerROS"
    ]
    ctl = lp.LocalController(
        lp.TrajectoryPlanner(lp.TrajectoryParams(**{**tp, "rotate_to_heading_threshold": 0.0}), cells, 0.05)
    )
    timings = {"new costmap": ([], []), "same costmap": ([], [])}
    warm = True
    for _, _, a, b, _ in problems[:5]:
        path, _ = gp.plan_cells(m.costs, a, b, cost_factor=3.0)
        x, y = m.cell_to_world(path[:, 0], path[:, 1])
        plan = np.column_stack([x, y, np.zeros(len(x))])
        for i in range(0, len(x) - 20, 10):
            window = cm.Costmap(120, 120, m.resolution, x[i] - 3.0, y[i] - 3.0)
            window.costs = cm.sample_static(window, m.costs, m.resolution, m.origin, 0.0, (0.0, 0.0, 0.0))
            window.costs[window.costs == cm.NO_INFORMATION] = 0
            yaw = math.atan2(y[i + 5] - y[i], x[i + 5] - x[i])
            if warm:  # numba's first calls compile or load their cache
                ctl.compute(window, (x[i], y[i], yaw), (0.3, 0.0), plan[i:], 0.05)
                window = window.copy()
                warm = False
            for label in timings:
                wall, cpu = timings[label]
                t, c = time.perf_counter(), time.thread_time()
                ctl.compute(window, (x[i], y[i], yaw), (0.3, 0.0), plan[i:], 0.05)
                wall.append(time.perf_counter() - t)
                cpu.append(time.thread_time() - c)
    print(
        f"\nTrajectoryPlanner cycle ({len(timings['new costmap'][0])} poses, vx_samples {tp['vx_samples']}, "
        f"vtheta_samples {tp['vtheta_samples']}, sim_time {tp['sim_time']} s; target < 5 ms):"
    )
    for label, (wall, cpu) in timings.items():
        print(
            f"  {label:13s} wall median {1e3 * np.median(wall):.2f} ms, p95 {1e3 * pct(wall, 95):.2f} ms; "
            f"thread CPU median {1e3 * np.median(cpu):.2f} ms, p95 {1e3 * pct(cpu, 95):.2f} ms"
        )
        result.add(
            f"local planner cycle, {label}: CPU median",
            1e3 * np.median(cpu),
            "ms thread CPU",
            target="< 5",
            headline=True,
        )


def timed_launch(
    launch_file: str, args: dict, duration: float
) -> tuple[float, float, float, float, float, float]:
    """(simulated s, running wall s, build wall s, process CPU s, main-thread CPU s, host steal
    share) of one launch run with its bag. Running wall time is the runner's own
    (RunResult.wall_time: from time 0 to the end, as the launch command's "simulated .. in .. s"
    line); build is the rest (parsing, building the diagram, loading numba's cached code, closing
    the bag). The steal share is the part of the machine's CPU time (both cores) that the
    hypervisor gave other guests meanwhile: this virtual machine's host is shared, and at times
    took 40-50% of it."""
    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import RunOptions, run

    plan = load_launch(PACKAGE_ROOT / launch_file, args)
    with tempfile.TemporaryDirectory() as tmp:
        cpu0, th0, wall0, steal0 = (
            time.process_time(),
            time.thread_time(),
            time.perf_counter(),
            host_steal_seconds(),
        )
        result = run(plan, RunOptions(duration=duration, bag=Path(tmp) / "bench.bag"))
        wall, cpu, th = time.perf_counter() - wall0, time.process_time() - cpu0, time.thread_time() - th0
        steal = (host_steal_seconds() - steal0) / (wall * (os.cpu_count() or 1))
    if result.error:
        raise result.error
    return result.sim_time, result.wall_time, wall - result.wall_time, cpu, th, steal


def launches(duration: float, repeats: int = 3, result=None) -> None:
    """The navigation launch (one goal across the house) on the saved house map and with gmapping
    building the map (the launch's default, as the original), against qbot_sim in the same world
    (robot, 1 kHz ros_control, laser, odometry, no navigation), all recording bags."""
    with tempfile.TemporaryDirectory() as tmp:
        rasterize.main([str(PACKAGE_ROOT / "sim/worlds/house.sdf"), "-o", str(Path(tmp) / "house")])
        world = str(PACKAGE_ROOT / "sim/worlds/house.sdf")
        runs = {
            "qbot_sim (no navigation)": ("launch/qbot_sim.launch.yaml", {"world": world}),
            "qbot_navigation, saved map": (
                "launch/qbot_navigation.launch.yaml",
                {"slam": "false", "map": str(Path(tmp) / "house.yaml"), "goal": "-3.3 2.4 0.0"},
            ),
            "qbot_navigation, gmapping": ("launch/qbot_navigation.launch.yaml", {"goal": "-3.3 2.4 0.0"}),
        }
        # rounds of all the launches in turn: the shared machine's speed drifts by tens of per
        # cent over minutes, so one launch against another is compared within a round, and
        # each figure is the median over the rounds
        rows = {label: [] for label in runs}
        for _ in range(repeats):
            for label, (f, a) in runs.items():
                rows[label].append(timed_launch(f, a, duration))
        print(
            f"\n{'launch (median of ' + str(repeats) + ' rounds)':34s} {'sim s':>6s} {'wall s':>7s} {'RTF':>6s} "
            f"{'RTF range':>11s} {'build s':>7s} {'CPU s':>6s} {'sim/CPU':>8s} {'thread CPU s':>12s} {'steal':>6s}"
        )
        for label, runs_ in rows.items():
            sim, wall, build, cpu, th, steal = np.median(np.array(runs_), axis=0)
            rtfs = [r[0] / r[1] for r in runs_]
            print(
                f"{label:34s} {sim:6.1f} {wall:7.1f} {sim / wall:6.2f} {min(rtfs):5.2f}-{max(rtfs):<5.2f} "
                f"{build:7.1f} {cpu:6.1f} {sim / cpu:8.2f} {th:12.1f} {100 * steal:5.0f}%"
            )
            if result is not None:
                result.add(
                    f"{label}: real-time factor",
                    sim / wall,
                    f"x real time (median of {repeats})",
                    target=">= 2",
                    headline=True,
                )
        print(
            "RTF: simulated / running wall seconds, build excluded (the machine is shared: sim/CPU is "
            "the figure without the other jobs' share; steal: the host's share of both cores meanwhile; "
            "target >= 2x)"
        )


if __name__ == "__main__":
    main()
