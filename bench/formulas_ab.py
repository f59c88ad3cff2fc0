"""The 1 kHz loops before and after the formulas were written once: the update() of the cart
controller and of qbot's skid-steer drive on an earlier commit's tree and on this checkout.

Each run is a child process with one tree's sources first on the path: the launch
(twil_cart_linearizing for --cart-seconds, qbot_sim for --qbot-seconds) run as the runner runs
it, every update() timed (bench/_common.instrumented_launch). The trees alternate within each of
--rounds rounds, after one untimed run of each (numba compiles into the tree's cache), so the
machine's drift touches both alike. Figures per loop and tree: the medians over the rounds of
update()'s median and p99 (wall) and p99 (thread CPU); and the p99 ratio now / before, which
must stay within 10%. --also NAME=COMMIT measures another tree beside them (e.g. an experiment).

    .venv/bin/python bench/formulas_ab.py [--before 2c75570] [--rounds 4] [--also NAME=COMMIT]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

from _result import ROOT, BenchResult, git_commit

HERE = Path(__file__).resolve().parent
BEFORE = "2c75570"  # the last commit before the formulas were written once
LOOPS = {
    "cart update()": ("launch/twil_cart_linearizing.launch.yaml", "cart_linearizing_controller"),
    "qbot drive update()": ("launch/qbot_sim.launch.yaml", "skid_steer_drive_controller"),
}

CHILD = """
import json, os, sys
import numpy as np
sys.path.insert(0, {bench!r})
from _common import instrumented_launch
run = instrumented_launch({launch!r}, {seconds!r}, controller={controller!r})
print(json.dumps({{"p50": float(np.median(run.update_wall_us)), "p99": float(np.percentile(run.update_wall_us, 99)),
                   "cpu_p99": float(np.percentile(run.update_cpu_us, 99)), "load": os.getloadavg()[0]}}))
"""


def extract(commit: str, folder: Path) -> Path:
    """The commit's tree, written into `folder` (git archive: the checkout is not touched)."""
    archive = folder / f"{commit}.tar"
    with open(archive, "wb") as f:
        done = subprocess.run(
            ["git", "archive", commit], cwd=ROOT, stdout=f, stderr=subprocess.PIPE, text=True, check=False
        )
    if done.returncode != 0:
        raise SystemExit(
            f"formulas_ab: git archive {commit}: {done.stderr.strip()} (a shallow clone lacks older "
            f"commits: git fetch --unshallow)"
        )
    tree = folder / commit
    with tarfile.open(archive) as tar:
        tar.extractall(tree, filter="data")
    return tree


def one_run(tree: Path, loop: str, seconds: float) -> dict:
    launch, controller = LOOPS[loop]
    code = CHILD.format(bench=str(HERE), launch=launch, seconds=seconds, controller=controller)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tree / "src"), os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=tree, env=env, capture_output=True, text=True, check=False
    )
    if done.returncode != 0:
        raise SystemExit(f"formulas_ab: {loop} on {tree.name} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--before", default=BEFORE, help=f"the earlier commit ({BEFORE})")
    p.add_argument("--rounds", type=int, default=4)
    p.add_argument("--cart-seconds", type=float, default=3.0, help="simulated seconds per cart run")
    p.add_argument("--qbot-seconds", type=float, default=5.0, help="simulated seconds per qbot run")
    p.add_argument(
        "--also", action="append", default=[], metavar="NAME=COMMIT", help="another tree to measure"
    )
    a = p.parse_args()
    extra = dict(item.split("=", 1) for item in a.also)
    result = BenchResult(
        "formulas_ab",
        "the 1 kHz update() of the cart controller and of qbot's drive inside their "
        "launches, on the tree before the formulas were written once and on this checkout, "
        "alternated in child processes",
    )
    seconds = {"cart update()": a.cart_seconds, "qbot drive update()": a.qbot_seconds}
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"before": extract(a.before, Path(tmp)), "now": ROOT}
        trees.update({name: extract(commit, Path(tmp)) for name, commit in extra.items()})
        for tree in trees.values():  # numba compiles into each tree's cache once
            for loop in LOOPS:
                one_run(tree, loop, 0.5)
        runs = {(loop, name): [] for loop in LOOPS for name in trees}
        for r in range(a.rounds):
            order = list(trees) if r % 2 == 0 else list(reversed(trees))
            for loop in LOOPS:
                for name in order:
                    runs[loop, name].append(one_run(trees[name], loop, seconds[loop]))
            print(
                f"round {r + 1}: "
                + "; ".join(
                    f"{loop} {name} p99 {runs[loop, name][-1]['p99']:.1f} us"
                    for loop in LOOPS
                    for name in trees
                ),
                flush=True,
            )
    commits = {"before": a.before, "now": git_commit(), **extra}
    for loop in LOOPS:
        for name in trees:
            rs, row = runs[loop, name], f"{loop}, {name} ({commits[name]})"
            result.add(
                "median", statistics.median(r["p50"] for r in rs), "us (median of the rounds)", row=row
            )
            result.add("p99", statistics.median(r["p99"] for r in rs), "us (median of the rounds)", row=row)
            result.add(
                "p99 thread CPU",
                statistics.median(r["cpu_p99"] for r in rs),
                "us (median of the rounds)",
                row=row,
            )
            result.add("p99 per round", ", ".join(f"{r['p99']:.1f}" for r in rs), "us", row=row)
            result.add(
                "load", statistics.median(r["load"] for r in rs), "1-min load average (median)", row=row
            )
            result.records[row] = rs
        ratio = statistics.median(r["p99"] for r in runs[loop, "now"]) / statistics.median(
            r["p99"] for r in runs[loop, "before"]
        )
        result.add(f"{loop} p99, now / before", ratio, target="<= 1.1", headline=True)
        print(f"{loop}: p99 now / before {ratio:.3f} (target <= 1.1)")
    result.write()


if __name__ == "__main__":
    main()
