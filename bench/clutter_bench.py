"""Navigation in clutter: BARN-like worlds from the BARN benchmark's own data (each world's cylinders
as an SDF, its start, goal and metric as BARN's run.py has them), for a Jackal-sized robot or qbot.

    .venv/bin/python bench/clutter_bench.py --barn DIR            # the test set (0, 6, ..., 294), kinematic
    .venv/bin/python bench/clutter_bench.py --barn DIR --worlds 6 12 18 --robot qbot --sim drake

DIR: a checkout (or bare repository) of github.com/Daffan/the-barn-challenge. --sim kinematic runs
move_base with --config's files (default config/jackal_nav) against a kinematic robot with a
ray-cast laser (bench/_kinematic_nav.py); --sim drake runs qbot's launch in the simulation. As
run.py: time from the first motion, success within 1 m, a collision ends the run, 100 s timeout.
"""

from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import _nav_worlds as worlds
from _barn_data import BarnSource, metric

ROOT = Path(__file__).resolve().parents[1]
TEST_SET = tuple(range(0, 300, 6))


def kinematic_episode(job: dict) -> dict:
    import _kinematic_nav as kn

    sc = job["scenario"]
    robot = kn.jackal(Path(job["config"])) if job["robot"] == "jackal" else kn.qbot()
    r = kn.run(sc, robot, job.get("params"), job["timeout"], 1.0, job["seed"], goal_frame=job["goal_frame"])
    return {
        "world": sc.info["world"],
        "status": r.status,
        "time_s": r.time_s,
        "final_m": r.final_m,
        "progress_m": r.end[0],  # the start frame's x is BARN's y - 3: metres made towards the goal
        "text": r.text,
        "wall_s": r.wall_s,
    }


def drake_episode(job: dict) -> dict:
    from _nav_episode import Episode, run_episode

    sc = job["scenario"]
    ep = Episode(
        sc, args={"slam": "true" if job["slam"] else "false"}, timeout=job["timeout"] + 10, seed=job["seed"]
    )
    row = run_episode(ep)
    status = "succeeded" if row.get("final_m", math.inf) <= 1.0 else "timeout"
    if row.get("contacts", 0) > 0:
        status = "collided"
    end = row.get("end_xy") or (math.nan, math.nan)
    return {
        "world": sc.info["world"],
        "status": status if row.get("status") != "ERROR" else "error",
        "time_s": row.get("time_s") or job["timeout"],
        "final_m": row.get("final_m", math.nan),
        "progress_m": end[0],
        "text": row.get("text") or row.get("error", ""),
        "wall_s": row.get("wall_s", math.nan),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--barn", type=Path, required=True, help="the-barn-challenge checkout or git repository")
    ap.add_argument("--worlds", type=int, nargs="+", default=TEST_SET)
    ap.add_argument("--robot", choices=("jackal", "qbot"), default="jackal")
    ap.add_argument("--sim", choices=("kinematic", "drake"), default="kinematic")
    ap.add_argument(
        "--config", type=Path, default=ROOT / "config/jackal_nav", help="the Jackal's parameter files"
    )
    ap.add_argument("--param", action="append", default=[], help="a move_base parameter NAME:=VALUE (YAML)")
    ap.add_argument("--slam", action="store_true", help="drake: gmapping instead of the rasterised map")
    ap.add_argument("--timeout", type=float, default=100.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--label", default="", help="a name for this configuration in the results")
    args = ap.parse_args(argv)
    import yaml
    from _common import BenchResult

    barn = BarnSource(args.barn)
    dwa = barn.dwa_rows()
    params = {k: yaml.safe_load(v) for k, v in (a.split(":=", 1) for a in args.param)}
    jobs = [
        {
            "scenario": worlds.barn_scenario(barn.world(i), i),
            "config": str(args.config),
            "robot": args.robot,
            "params": params,
            "timeout": args.timeout,
            "seed": args.seed,
            "slam": args.slam,
            # BARN's goal is in odom; qbot's launch takes it in map (the same frame here)
            "goal_frame": "odom" if args.robot == "jackal" else "map",
        }
        for i in args.worlds
    ]
    run = kinematic_episode if args.sim == "kinematic" else drake_episode
    label = (
        args.label or f"{args.robot} {args.sim} {args.config.name if args.robot == 'jackal' else ''}".strip()
    )
    print(f"{label}: {len(jobs)} worlds")
    print(f"{'world':>5} {'status':>9} {'time s':>7} {'metric':>6} {'made m':>6}  Gazebo DWA ok/10  note")
    rows = []
    ctx = get_context("spawn")
    with ProcessPoolExecutor(
        args.jobs, mp_context=ctx, max_tasks_per_child=1 if args.sim == "drake" else None
    ) as pool:
        for row in pool.map(run, jobs):
            i = row["world"]
            row["metric"] = metric(row["status"] == "succeeded", row["time_s"], barn.path_length(i))
            d = dwa.get(i, [])
            row["dwa_success"] = sum(r[0] for r in d) / len(d) if d else math.nan
            rows.append(row)
            print(
                f"{i:5d} {row['status']:>9} {row['time_s']:7.1f} {row['metric']:6.3f} {row['progress_m']:6.2f}  "
                f"{sum(r[0] for r in d):2d}/{len(d):<2d}            {row['text'][:70]}",
                flush=True,
            )
    n = len(rows)
    share = {
        s: sum(r["status"] == s for r in rows) / n for s in ("succeeded", "collided", "timeout", "aborted")
    }
    mean_metric = sum(r["metric"] for r in rows) / n
    ok_times = [r["time_s"] for r in rows if r["status"] == "succeeded"]
    dwa_all = [r for i in args.worlds for r in dwa.get(i, [])]
    dwa_success = sum(r[0] for r in dwa_all) / len(dwa_all) if dwa_all else math.nan
    dwa_metric = sum(r[4] for r in dwa_all) / len(dwa_all) if dwa_all else math.nan
    print(
        f"\nsuccess {share['succeeded']:.3f}, collisions {share['collided']:.3f}, timeouts {share['timeout']:.3f}, "
        f"aborted {share['aborted']:.3f}; mean metric {mean_metric:.4f}; mean time of the successes "
        f"{(sum(ok_times) / len(ok_times)) if ok_times else math.nan:.1f} s "
        f"(Gazebo DWA on these worlds: success {dwa_success:.3f}, its logged metric {dwa_metric:.4f})"
    )
    result = BenchResult(
        "clutter_bench",
        "navigation through BARN's cylinder fields (worlds generated from BARN's data): success, "
        "collisions, timeouts and BARN's metric, beside Gazebo's DWA runs",
    )
    result.add("configuration", label)
    result.add("worlds", n)
    result.add(
        "success", share["succeeded"], "share", target=">= 0.95", headline=f"clutter ({label}): success"
    )
    result.add("collisions", share["collided"], "share")
    result.add("timeouts", share["timeout"], "share")
    result.add("aborted", share["aborted"], "share")
    result.add("mean_metric", mean_metric, "BARN metric", headline=f"clutter ({label}): mean BARN metric")
    result.add("gazebo_dwa_success", dwa_success, "share of 10 runs a world")
    result.records = {"rows": rows}
    result.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
