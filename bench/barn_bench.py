"""The BARN benchmark's test set as its users run it (test.sh: 50 worlds 0, 6, ..., 294, ten
trials each, jackal_helper's move_base_DWA.launch as it is) through ``python -m
twil_control.barn --worlds ... --runs ...`` on the local Dask cluster, beside Gazebo's rows
(the-barn-challenge's res/dwa_out.txt): success, collision, timeout and metric world by world
and overall, the wall time and the CPU time, and a figure of success by world in order of
difficulty, Gazebo against this project.

    .venv/bin/python bench/barn_bench.py [--src CATKIN_SRC] [--worlds 0:300:6] [--runs 10]
        [--workers N] [--dir DIR] [--from-records DIR]

The catkin src holds the-barn-challenge, jackal and jackal_simulator (as BARN's
Singularityfile.def clones them); the description packages the Jackal's xacro includes
(sick_tim, lms1xx, pointgrey_camera_description, ...) come from ROS_PACKAGE_PATH, else the
stand-ins in tests/data/ros1. Trials are recorded in --dir and a rerun skips them (resumable);
--from-records DIR only reads a run's records. Difficulty order: BARN numbers its worlds by its
difficulty metrics (the metrics files are not in the-barn-challenge); the bench checks it with
the mean clearance along each world's optimal path (BARN's distance-to-closest-obstacle, from
the world and path files) and prints the rank correlations.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from _result import ROOT, BenchResult, figure_path

ROS1 = ROOT / "tests" / "data" / "ros1"
RADIUS = 0.075


@dataclass(frozen=True)
class Stack:
    """The navigation stack a run measures, and how its results are named."""

    name: str  # the results' name (bench/NAME.py)
    title: str
    label: str  # this project's rows on the page and in the figure
    targets: dict  # figure -> "OP NUMBER", or "OP gazebo": Gazebo DWA's figure on the same worlds
    nav_launch: Path | None = None  # None: jackal_helper's move_base_DWA.launch, as run.py

    @property
    def image(self) -> Path:
        return figure_path(f"{self.name.removesuffix('_bench')}_success_by_world.png")


DWA = Stack(
    "barn_bench",
    "The BARN test set with jackal_helper's move_base_DWA.launch as it is: this project's success, "
    "collision, timeout and metric (report_test.py's arithmetic) beside Gazebo's (res/dwa_out.txt), "
    "world by world, and the wall and CPU time of the whole set on this machine's cores.",
    "this project",
    {"success": ">= 0.85", "collision": "<= 0.056"},
)


def cell_to_world(cells: np.ndarray) -> np.ndarray:
    return np.column_stack(
        [cells[:, 0] * 2 * RADIUS - RADIUS - 60 * RADIUS, cells[:, 1] * 2 * RADIUS + RADIUS + 5]
    )


def optimal_time(helper: Path, idx: int) -> float:
    """report_test.py's optimal time (its start (-2, 3))."""
    cells = np.load(helper / "worlds" / "BARN" / "path_files" / f"path_{idx}.npy").astype(float)
    points = np.vstack([(-2.0, 3.0), cell_to_world(cells), (-2.0, 13.0)])
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum()) / 2


def clearance(helper: Path, idx: int) -> float:
    """Mean distance (m) from the optimal path's cells to the nearest cylinder's surface."""
    text = (helper / "worlds" / "BARN" / f"world_{idx}.world").read_text()
    head = text.split("<state", 1)[0]
    centres = np.array(
        [
            [float(v) for v in m.group(1).split()[:2]]
            for m in re.finditer(
                r"<model name='unit_cylinder_\d+'>\s*<static>1</static>\s*<pose[^>]*>([^<]+)<", head
            )
        ]
    )
    path = cell_to_world(np.load(helper / "worlds" / "BARN" / "path_files" / f"path_{idx}.npy").astype(float))
    d = np.linalg.norm(path[:, None, :] - centres[None, :, :], axis=2).min(axis=1) - RADIUS
    return float(d.mean())


def read_out(text: str) -> dict[int, list[tuple]]:
    rows = defaultdict(list)
    for line in text.splitlines():
        f = line.split()
        if len(f) == 6:
            rows[int(f[0])].append((int(f[1]), int(f[2]), int(f[3]), float(f[4])))
    return rows


def world_stats(rows: list[tuple], best: float) -> dict:
    """report_test.py's per-world means (its metric from the time, as it recomputes it)."""
    metric = [s * best / np.clip(t, 2 * best, 8 * best) for s, _, _, t in rows]
    succeeded = [t for s, _, _, t in rows if s]
    return {
        "runs": len(rows),
        "success": float(np.mean([r[0] for r in rows])),
        "collision": float(np.mean([r[1] for r in rows])),
        "timeout": float(np.mean([r[2] for r in rows])),
        "metric": float(np.mean(metric)),
        "time": float(np.mean(succeeded)) if succeeded else float("nan"),
    }


def overall(stats: dict[int, dict]) -> dict:
    times = [s["time"] for s in stats.values() if not np.isnan(s["time"])]
    out = {
        k: float(np.mean([s[k] for s in stats.values()]))
        for k in ("success", "collision", "timeout", "metric")
    }
    out["time"] = float(np.mean(times)) if times else float("nan")
    return out


def find_src(arg: str | None) -> Path:
    if arg:
        return Path(arg).absolute()
    for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
        for helper in Path(entry).glob("**/jackal_helper/package.xml") if entry else []:
            return helper.parents[1].parent
    sys.exit(
        "barn_bench: give --src CATKIN_SRC (the-barn-challenge, jackal, jackal_simulator) or put it on ROS_PACKAGE_PATH"
    )


def plot(order: list[int], ours: dict[int, dict], gazebo: dict[int, dict], path: Path, stack: Stack) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.arange(len(order))
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(11, 6), sharex=True)
    labels = ("Gazebo + ROS move_base DWA (res/dwa_out.txt)", f"twil_control: {stack.label}")
    ax.bar(x - 0.2, [gazebo[w]["success"] for w in order], 0.4, label=labels[0])
    ax.bar(x + 0.2, [ours[w]["success"] for w in order], 0.4, label=labels[1])
    ax.set_ylabel("success rate")
    ax.set_ylim(0, 1.05)
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title(f"BARN test set, world by world: {stack.label} against Gazebo's DWA")
    bx.bar(x - 0.2, [gazebo[w]["time"] for w in order], 0.4, label=labels[0])
    bx.bar(x + 0.2, [ours[w]["time"] for w in order], 0.4, label=labels[1])
    bx.set_ylabel("mean time of a success (s)")
    bx.set_xticks(x, [str(w) for w in order], rotation=90, fontsize=7)
    bx.set_xlabel("BARN world (BARN numbers its worlds from easy to hard)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None, stack: Stack = DWA) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--src", help="catkin src holding the-barn-challenge, jackal, jackal_simulator")
    ap.add_argument("--worlds", default="0:300:6")
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--workers", type=int)
    ap.add_argument("--dir", type=Path, default=ROOT / "runs" / stack.name)
    ap.add_argument(
        "--from-records", type=Path, metavar="DIR", help="read these records (an out.txt beside), run nothing"
    )
    a = ap.parse_args(argv)
    src = find_src(a.src)
    helper = src / "the-barn-challenge" / "jackal_helper"
    gazebo_file = src / "the-barn-challenge" / "res" / "dwa_out.txt"
    if not gazebo_file.is_file():
        gazebo_file = ROS1 / "vendor" / "the-barn-challenge" / "res" / "dwa_out.txt"
    result = BenchResult(stack.name, stack.title)
    records = a.from_records or a.dir
    out = records / "out.txt"
    wall = None
    if a.from_records is None:
        env = dict(os.environ)
        extra = [str(src), str(ROS1 / "stubs"), str(ROS1 / "vendor")]
        env["ROS_PACKAGE_PATH"] = os.pathsep.join([p for p in [env.get("ROS_PACKAGE_PATH", "")] if p] + extra)
        command = [sys.executable, "-m", "twil_control.barn", "--worlds", a.worlds, "--runs", str(a.runs)]
        command += ["--out", str(out), "--dir", str(records)]
        command += ["--workers", str(a.workers)] if a.workers else []
        command += ["--nav_launch", str(stack.nav_launch)] if stack.nav_launch else []
        records.mkdir(parents=True, exist_ok=True)
        start = time.perf_counter()
        code = subprocess.run(command, env=env, cwd=ROOT).returncode
        wall = time.perf_counter() - start
        if code == 2:  # twil_control.barn refused the set before any trial (its message is above)
            print(f"{stack.name}: no trial could start; no result written", file=sys.stderr)
            return 2
    # every recorded trial's line (a run still going, or stopped, leaves the finished ones)
    ours_rows = read_out("".join(p.read_text() for p in sorted((records / "runs").glob("run_*.txt"))))
    gazebo_rows = read_out(gazebo_file.read_text())
    worlds = sorted(ours_rows)
    best = {w: optimal_time(helper, w) for w in worlds}
    ours = {w: world_stats(ours_rows[w], best[w]) for w in worlds}
    gazebo = {w: world_stats(gazebo_rows[w], best[w]) for w in worlds}
    difficulty = {w: clearance(helper, w) for w in worlds}
    order = worlds  # BARN's own difficulty order
    if len(worlds) > 2:
        from scipy.stats import spearmanr

        succ = [gazebo[w]["success"] for w in worlds]
        result.add("rank correlation, index and Gazebo success", spearmanr(worlds, succ).statistic)
        result.add(
            "rank correlation, index and path clearance",
            spearmanr(worlds, [difficulty[w] for w in worlds]).statistic,
        )
        result.add(
            "rank correlation, index and this project's success",
            spearmanr(worlds, [ours[w]["success"] for w in worlds]).statistic,
        )
    for w in order:
        row = f"world {w}"
        result.add("clearance", difficulty[w], "m", row=row, table="by world")
        for who, stats in (("gazebo", gazebo[w]), ("ours", ours[w])):
            for k in ("success", "collision", "timeout", "metric"):
                result.add(f"{who} {k}", stats[k], row=row, table="by world")
        result.add("ours runs", ours[w]["runs"], row=row, table="by world")
    totals = {"gazebo": overall(gazebo), "ours": overall(ours)}
    for who, t in totals.items():
        for k, v in t.items():
            target = stack.targets.get(k) if who == "ours" else None
            if target and "gazebo" in target:  # a target relative to Gazebo's DWA on the same worlds
                target = target.replace("gazebo", f"{totals['gazebo'][k]:.4f}")
            headline = (
                f"BARN {k}, {stack.label if who == 'ours' else 'Gazebo'}"
                if k in ("success", "collision", "metric") and (who == "ours" or stack is DWA)
                else False
            )
            result.add(k, v, "s" if k == "time" else "", row=who, target=target, headline=headline)
    trials = sum(len(r) for r in ours_rows.values())
    result.add("worlds", len(worlds))
    result.add("trials", trials)
    runs_dir = records / "runs"
    recs = [json.loads(p.read_text()) for p in sorted(runs_dir.glob("run_*.json")) if ".stats" not in p.name]
    stats = [json.loads(p.read_text()) for p in sorted(runs_dir.glob("run_*.stats.json"))]
    if stats:
        sim, run_cpu = sum(x["sim_time"] for x in stats), sum(x["run_cpu"] for x in stats)
        result.add("start-up to time 0, wall (median)", np.median([x["startup_wall"] for x in stats]), "s")
        result.add(
            "start-up to time 0, CPU (median, this process)",
            np.median([x["process_cpu"] - x["run_cpu"] for x in stats]),
            "s",
        )
        result.add("simulated time per trial (mean)", sim / len(stats), "s")
        result.add(
            "real-time factor, CPU (simulated s per CPU s)",
            sim / run_cpu,
            "x",
            target=">= 4",
            headline=stack is DWA,
        )
        result.add("real-time factor, wall", sim / sum(x["run_wall"] for x in stats), "x")
    cpu = sum(r.get("cpu_time") or 0.0 for r in recs)
    result.add("CPU time, all trials", cpu, "s")
    result.add(
        "CPU time per trial", cpu / max(len(recs), 1), "s", headline=stack is DWA and "BARN CPU per trial"
    )
    result.add(
        "wall time per trial, one worker",
        float(np.mean([r["wall_time"] for r in recs])) if recs else 0.0,
        "s",
    )
    if wall is not None:
        result.add("wall time, this run", wall, "s", headline=stack is DWA and "BARN wall time")
        if trials == 500:
            result.add("test set in under 1 hour", wall < 3600)
    result.records = {"ours": {str(w): ours_rows[w] for w in worlds}}
    image = stack.image
    plot(order, ours, gazebo, image, stack)
    result.image = str(image.relative_to(ROOT) if image.is_relative_to(ROOT) else image)
    for who, t in totals.items():
        print(f"{who:7s} " + ", ".join(f"{k} {v:.4f}" for k, v in t.items()))
    print(
        f"{trials} trials in {len(worlds)} worlds; CPU {cpu:.0f} s" + (f", wall {wall:.0f} s" if wall else "")
    )
    result.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
