"""One navigation episode of a generated world, in a process of its own (pydrake never frees a
diagram that holds a Python system), and many of them in a process pool: the world written as
SDF, rasterised for the ground-truth map, a navigation launch run to one goal, the bag analysed
(status and its text, time, final distance, contacts, least clearance, where the robot ended).
"""

from __future__ import annotations

import math
import shutil
import tempfile
import time
import traceback
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path

from twil_control import PACKAGE_ROOT

QBOT_LAUNCH = PACKAGE_ROOT / "launch/qbot_navigation.launch.yaml"


@dataclass
class Episode:
    scenario: object  # _nav_worlds.Scenario, in the start's frame
    launch: Path = QBOT_LAUNCH
    args: dict = field(default_factory=dict)  # launch args besides world, goal (and map)
    timeout: float = 150.0  # simulated seconds
    seed: int = 0
    tolerance: float = 0.5  # m: the goal tolerance move_base judges the robot's estimate by
    # m: how far beyond `tolerance` the true pose may be (the SLAM estimate's error at the goal,
    # up to 8 cm measured): reached = SUCCEEDED with the truth within tolerance + this
    localisation_allowance: float = 0.05
    keep: Path | None = None  # copy the bag (and the world) here
    keep_failures_only: bool = True
    map_height: float = 0.135  # the scan plane, for the rasterised map


def run_episode(ep: Episode) -> dict:
    """Row of one episode (never raises: an exception is the row's `error`)."""
    import _nav_worlds

    from twil_control.bag.analyses import navigation as nav_analysis
    from twil_control.bag.reader import Bag
    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import RunOptions, run
    from twil_control.tools import rasterize

    sc = ep.scenario
    row = {"name": sc.name, **sc.info}
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        try:
            world = _nav_worlds.write_world(sc, tmp)
            rasterize.main([str(world), "-o", str(tmp / "truth"), "--height", str(ep.map_height)])
            gx, gy, gyaw = sc.goal
            args = {"world": str(world), "goal": f"{gx:.4f} {gy:.4f} {gyaw:.4f}", **ep.args}
            if str(args.get("slam", "true")).lower() == "false":
                args.setdefault("map", str(tmp / "truth.yaml"))
            plan = load_launch(ep.launch, args)
            bag = tmp / f"{sc.name}.bag"
            wall0, cpu0 = time.perf_counter(), time.process_time()
            result = run(plan, RunOptions(duration=ep.timeout, bag=bag, seed=ep.seed))
            row["wall_s"] = time.perf_counter() - wall0
            row["cpu_s"] = time.process_time() - cpu0
            row["sim_s"] = result.sim_time
            if result.error:
                raise result.error
            b = Bag(bag)
            topics = nav_analysis.detect(b)
            metrics = nav_analysis.analyze(b, topics, {"ground_truth_map": str(tmp / "truth.yaml")}).metrics
            goals = metrics["per_goal"]
            g = goals[0] if goals else {"status": "NO_GOAL"}
            texts = (
                [m.status.text for _, m in b.messages("/move_base/result")]
                if "/move_base/result" in b.topics
                else []
            )
            row.update(
                status=g["status"],
                text=texts[-1] if texts else "",
                time_s=g.get("time_s"),
                final_m=g.get("final_distance_m", math.nan),
                end_xy=(g.get("end_x_m"), g.get("end_y_m")),
                path_m=g.get("path_length_m"),
                clearance_m=g.get("min_clearance_m"),
                contacts=int(g.get("collision_samples", 0)),
            )
            row["reached"] = reached(row, ep.tolerance + ep.localisation_allowance)
            if ep.keep is not None and (not ep.keep_failures_only or not row["reached"]):
                ep.keep.mkdir(parents=True, exist_ok=True)
                shutil.copy(bag, ep.keep / bag.name)
                shutil.copy(world, ep.keep / world.name)
        except Exception as exc:  # noqa: BLE001 - a row per episode, the error in it
            row.update(status="ERROR", reached=False, error=f"{type(exc).__name__}: {exc}")
            row["traceback"] = traceback.format_exc(limit=6)
    return row


def reached(row: dict, within: float) -> bool:
    """move_base SUCCEEDED and the true final pose within `within` m of the goal."""
    return row.get("status") == "SUCCEEDED" and row.get("final_m", math.inf) <= within + 1e-6


def run_many(episodes: list[Episode], jobs: int = 1, on_row=None, budget: float | None = None) -> list[dict]:
    """Every episode in a fresh process (`jobs` at a time); rows in the episodes' order. With a
    `budget` (s of wall time), the episodes not started when it has run out are left out."""
    rows: list[dict | None] = [None] * len(episodes)
    end = None if budget is None else time.perf_counter() + budget
    with ProcessPoolExecutor(jobs, mp_context=get_context("spawn"), max_tasks_per_child=1) as pool:
        futures = {pool.submit(run_episode, ep): i for i, ep in enumerate(episodes)}
        for fut in futures:
            if fut.cancelled():
                continue
            i = futures[fut]
            rows[i] = fut.result()
            if on_row is not None:
                on_row(rows[i])
            if end is not None and time.perf_counter() > end:
                for other in futures:
                    other.cancel()  # only those not running yet
    return [r for r in rows if r is not None]
