#!/usr/bin/env python3
"""Two runs of the cart_linearizing_controller in Drake, side by side.

Run:  .venv/bin/python docs/scripts/plot_cart_drake.py [--compare law|platform_constants]
                                                       [--duration S] [--goal "x y theta"] [--out docs/img]

Runs launch/twil_cart_linearizing.launch.yaml twice from (0, 0, 0) to the same goal, pose from
ground truth, with the same arm program, changing one launch argument:
- law (default): the corrected law against the paper's (51)-(52) as printed
  -> docs/img/drake_corrected_vs_printed.png (15 s);
- platform_constants: K5..K8 derived from the description against the lab's identified ones
  -> docs/img/drake_derived_vs_identified.png (30 s).
The figure's columns are the cart analysis's own panels (bag/analyses/cart.py): e, alpha, psi;
V1; the wheel torques; the path. Prints each run's summary (bag report's lines).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from twil_control import PACKAGE_ROOT  # noqa: E402
from twil_control.bag.analyses import cart  # noqa: E402
from twil_control.bag.analyze import run_analyses  # noqa: E402
from twil_control.bag.reader import Bag  # noqa: E402
from twil_control.bag.report import summary_text  # noqa: E402
from twil_control.launch.loader import load_launch  # noqa: E402
from twil_control.launch.runner import RunOptions, run  # noqa: E402

COMPARISONS = {
    "law": (("corrected", "printed"), 15.0),
    "platform_constants": (("derived", "identified"), 30.0),
}
PANELS = ("cart_polar", "cart_v1", "cart_torques", "cart_path")


def run_case(arg: str, value: str, goal: str, duration: float, bag: Path):
    """The cart analysis of one run (its Result)."""
    plan = load_launch(
        PACKAGE_ROOT / "launch/twil_cart_linearizing.launch.yaml",
        {arg: value, "goal": goal, "pose_source": "ground_truth"},
    )
    result = run(plan, RunOptions(duration=duration, bag=bag))
    if result.error:
        raise result.error
    results, skipped = run_analyses(Bag(bag), {"only": [cart.NAME]})
    if cart.NAME not in results:
        raise RuntimeError(f"{bag}: {skipped}")
    return results[cart.NAME]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--compare", choices=sorted(COMPARISONS), default="law")
    parser.add_argument(
        "--duration", type=float, help="simulated seconds (default: 15 for law, 30 for platform_constants)"
    )
    parser.add_argument("--goal", default="2 1 1.5707963267948966", help='"x y theta"')
    parser.add_argument("--out", type=Path, default=PACKAGE_ROOT / "docs/img")
    args = parser.parse_args()
    values, duration = COMPARISONS[args.compare]
    duration = args.duration or duration
    with tempfile.TemporaryDirectory() as tmp:
        results = {v: run_case(args.compare, v, args.goal, duration, Path(tmp) / f"{v}.bag") for v in values}
    fig = plt.figure(figsize=(13, 19), layout="constrained")
    grid = fig.add_gridspec(len(PANELS), 2, height_ratios=[1.4, 1.0, 1.0, 1.2])
    for col, (value, result) in enumerate(results.items()):
        figures = {f.name: f for f in result.figures}
        for row, name in enumerate(PANELS):
            sub = fig.add_subfigure(grid[row, col])
            figures[name].draw(sub)
            sub.suptitle(f"{args.compare} {value}: {figures[name].title}", fontsize=9)
        print(f"{args.compare} {value}: " + summary_text(result.metrics))
    fig.suptitle(
        f"cart_linearizing_controller in Drake (TWIL + WAM, ground-truth pose, {duration:g} s): "
        f"{args.compare} {values[0]} (left) and {values[1]} (right)",
        fontsize=11,
    )
    args.out.mkdir(parents=True, exist_ok=True)
    out = args.out / f"drake_{values[0]}_vs_{values[1]}.png"
    fig.savefig(out, dpi=70)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
