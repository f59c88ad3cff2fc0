"""qbot reaching seeded random goals on the house world through move_base, in one launch run.

    .venv/bin/python bench/nav_goals.py [--goals 20] [--seed 0] [--planner navfn/NavfnROS]
    .venv/bin/python bench/nav_goals.py --launch my_navigation.launch --goal-timeout 120

--launch runs another navigation launch (a user's own, e.g. with its original move_base files)
on the same goals: it must declare the args slam, map and goals_file as
launch/qbot_navigation.launch.yaml does; --goal-timeout cancels a goal without a result after
that many simulated seconds (move_base with oscillation_timeout 0 may never give up).

The house world (sim/worlds/house.sdf) rasterised at 0.05 m is served as a saved map
(slam:=false, fake localisation); goals are drawn by twil_control.navigation.evaluation (free
cells beyond the inflation radius, reachable from the spawn, 2 m apart, random yaw), sent one
after another by the launch's goal sender. The bag is analysed with the navigation analysis:
per goal its status, time, the driven path (ground truth) against the grid optimum between the
same start and end points (8-connected, through cells below INSCRIBED), the least clearance of the
base's centre, and the simulator's contacts of the qbot with anything but the floor.
Prints the table and the must-hold criteria (>= 95 % reached, no collision, mean path length
within 15 % of the optimum), with the run's real-time factor and its CPU time.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from twil_control import PACKAGE_ROOT
from twil_control.bag.analyses import navigation as nav_analysis
from twil_control.bag.reader import Bag
from twil_control.launch.loader import declared_args, load_launch
from twil_control.launch.runner import RunOptions, run
from twil_control.mapping.map_io import read_map
from twil_control.navigation import evaluation as ev
from twil_control.navigation.footprint import FootprintCells, parse_footprint
from twil_control.tools import rasterize

LAUNCH = PACKAGE_ROOT / "launch/qbot_navigation.launch.yaml"


def house_map(tmp: Path):
    """(map yaml path, costmap, footprint cells) of the house world at 0.05 m."""
    rasterize.main([str(PACKAGE_ROOT / "sim/worlds/house.sdf"), "-o", str(tmp / "house")])
    occ = read_map(tmp / "house.yaml")
    common = yaml.safe_load((PACKAGE_ROOT / "config/costmap_common_params.yaml").read_text())
    cells = FootprintCells(
        parse_footprint(common["footprint"], common.get("footprint_padding", 0.0)), occ.resolution
    )
    m = ev.costmap_from_occupancy(
        occ.data, occ.resolution, occ.origin, cells, common["inflation_radius"], common["cost_scaling_factor"]
    )
    return tmp / "house.yaml", m, cells


def run_goals(
    goals,
    seed: int,
    tmp: Path,
    map_yaml: Path,
    args: dict | None = None,
    duration: float | None = None,
    launch: Path = LAUNCH,
    goal_timeout: float = 0.0,
) -> tuple[dict, object, dict]:
    """Run the navigation launch through `goals`; (navigation analysis metrics, run result,
    timing: wall, process CPU and main-thread CPU seconds)."""
    goals_file = tmp / "goals.yaml"
    goals_file.write_text(yaml.safe_dump([{"x": x, "y": y, "yaw": yaw} for x, y, yaw in goals]))
    declared = declared_args(launch)
    plan = load_launch(
        launch,
        {
            "slam": "false",
            "map": str(map_yaml),
            "goals_file": str(goals_file),
            **{k: v for k, v in (args or {}).items() if k in declared},
        },
    )
    if goal_timeout:
        plan.params.set("/goals/timeout", float(goal_timeout))
    bag = tmp / f"goals_seed{seed}.bag"
    cpu0, thread0, wall0 = time.process_time(), time.thread_time(), time.perf_counter()
    result = run(plan, RunOptions(duration=duration, bag=bag, seed=seed))
    timing = {
        "wall_s": time.perf_counter() - wall0,
        "cpu_s": time.process_time() - cpu0,
        "thread_cpu_s": time.thread_time() - thread0,
    }
    if result.error:
        raise result.error
    b = Bag(bag)
    topics = nav_analysis.detect(b)
    metrics = nav_analysis.analyze(b, topics, {}).metrics
    return metrics, result, timing


def score(metrics: dict, m, tolerance: float) -> list[dict]:
    """Per goal: reached (SUCCEEDED and within tolerance), collisions, driven / optimum length."""
    rows = []
    for r in metrics["per_goal"]:
        row = dict(r)
        row["reached"] = (
            r["status"] == "SUCCEEDED" and r.get("final_distance_m", math.inf) <= tolerance + 1e-6
        )
        try:  # the optimum between where this goal started and where the robot stopped
            row["optimum_m"] = ev.grid_optimum(
                m, (r["start_x_m"], r["start_y_m"]), (r["end_x_m"], r["end_y_m"])
            )
        except Exception as exc:  # noqa: BLE001 - reported in the table
            row["optimum_m"] = math.nan
            row["note"] = str(exc)
        row["ratio"] = row["path_length_m"] / row["optimum_m"] if row["optimum_m"] > 0.05 else math.nan
        rows.append(row)
    return rows


def report(rows: list[dict], timing: dict, sim_time: float, min_reached: float = 0.95, result=None) -> bool:
    print(
        f"{'goal':>4} {'target x, y, yaw':>22} {'status':>10} {'time s':>7} {'driven m':>9} {'optimum m':>9} "
        f"{'ratio':>6} {'final m':>7} {'clear m':>7} {'contacts':>8}"
    )
    for r in rows:
        print(
            f"{r['goal'] + 1:4d} {r['target_x_m']:8.2f},{r['target_y_m']:6.2f},{r.get('target_yaw', 0):6.2f} "
            f"{r['status']:>10} {r['time_s'] if r['time_s'] is not None else math.nan:7.1f} "
            f"{r['path_length_m']:9.2f} {r['optimum_m']:9.2f} {r['ratio']:6.3f} {r.get('final_distance_m', math.nan):7.3f} "
            f"{r.get('min_clearance_m') or math.nan:7.3f} {r.get('collision_samples', 0):8d}"
        )
    n = len(rows)
    reached = sum(r["reached"] for r in rows)
    contacts = sum(r.get("collision_samples", 0) for r in rows)
    ratios = [r["ratio"] for r in rows if r["reached"] and np.isfinite(r["ratio"])]
    mean_ratio = float(np.mean(ratios)) if ratios else math.nan
    need = math.ceil(min_reached * n)
    ok = reached >= need and contacts == 0 and mean_ratio <= 1.15
    print(
        f"\nreached {reached}/{n} (need {need}); contact samples with the world {contacts} (need 0); "
        f"mean driven / optimum {mean_ratio:.3f} over the reached goals (need <= 1.15): "
        f"{'ALL MET' if ok else 'NOT MET'}"
    )
    print(
        f"simulated {sim_time:.1f} s in {timing['wall_s']:.1f} s wall ({sim_time / timing['wall_s']:.2f}x real time), "
        f"process CPU {timing['cpu_s']:.1f} s ({sim_time / timing['cpu_s']:.2f}x per CPU second), "
        f"main thread CPU {timing['thread_cpu_s']:.1f} s"
    )
    if result is not None:
        result.add("goals", n)
        result.add(
            "reached",
            reached / n,
            "share of the goals",
            target=">= 0.95",
            headline="seeded house goals reached",
        )
        result.add(
            "contact_samples",
            contacts,
            "samples touching the world",
            target="== 0",
            headline="seeded house goals: contact samples",
        )
        result.add(
            "driven_over_optimum",
            mean_ratio,
            "mean over the reached goals",
            target="<= 1.15",
            headline="seeded house goals: driven path / optimum",
        )
        result.add("simulated_s", sim_time, "s")
        result.add("rtf", sim_time / timing["wall_s"], "x real time")
    return ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--goals", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0, help="goal sampling and the launch's --seed")
    ap.add_argument("--planner", default="navfn/NavfnROS", help="base_global_planner")
    ap.add_argument("--ompl-planner", default="RRTConnect")
    ap.add_argument("--duration", type=float, default=None, help="simulated seconds at most")
    ap.add_argument("--keep", type=Path, default=None, help="copy the bag here")
    ap.add_argument("--launch", type=Path, default=LAUNCH, help="the navigation launch to run")
    ap.add_argument(
        "--goal-timeout",
        type=float,
        default=0.0,
        help="cancel a goal without a result after this many simulated seconds (0: none)",
    )
    args = ap.parse_args(argv)
    from _common import (
        BenchResult,  # here: the tests import this module's helpers without bench/ on the path
    )

    result = BenchResult(
        "nav_goals",
        "qbot reaching seeded random goals in the house through move_base on the saved "
        "map, in one launch run: goals reached, contacts, driven path against the grid optimum",
    )
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        map_yaml, m, cells = house_map(tmp)
        goals = ev.sample_goals(m, cells, (0.0, 0.0, 0.0), args.goals, np.random.default_rng(args.seed))
        metrics, run_result, timing = run_goals(
            goals,
            args.seed,
            tmp,
            map_yaml,
            {"global_planner": args.planner, "ompl_planner": args.ompl_planner},
            args.duration,
            args.launch.absolute(),
            args.goal_timeout,
        )
        tol = yaml.safe_load((PACKAGE_ROOT / "config/base_local_planner_params.yaml").read_text())[
            "TrajectoryPlannerROS"
        ]["xy_goal_tolerance"]
        for r, g in zip(metrics["per_goal"], goals):
            r["target_yaw"] = g[2]
        print(
            f"{args.launch.name}: house.sdf, {args.goals} goals (seed {args.seed}), {args.planner}"
            f"{' ' + args.ompl_planner if 'ompl' in args.planner else ''}"
        )
        ok = report(score(metrics, m, tol), timing, run_result.sim_time, result=result)
        if args.keep:
            import shutil

            shutil.copy(tmp / f"goals_seed{args.seed}.bag", args.keep)
    result.write()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
