"""What the Meshcat view costs the simulation: the qbot navigation launch run as fast as possible,
headless and then with the view recording (--save-html: Meshcat, MeshcatVisualizer and every
layer drawn, no browser), alternately, `--repeats` times each; prints the wall times and the ratio.

    .venv/bin/python bench/view_overhead.py --duration 10 --repeats 2
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _common import BenchResult

ROOT = Path(__file__).resolve().parents[1]


def run(args: list[str], cwd: Path) -> tuple[float, float]:
    out = subprocess.run(
        [sys.executable, "-m", "twil_control.launch", *args], cwd=cwd, capture_output=True, text=True
    )
    m = re.search(r"simulated ([\d.]+) s in ([\d.]+) s", out.stderr + out.stdout)
    if out.returncode != 0 or not m:
        raise SystemExit(f"launch failed ({out.returncode}):\n{out.stderr[-2000:]}")
    return float(m.group(1)), float(m.group(2))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=10.0, help="simulated seconds per run")
    p.add_argument("--repeats", type=int, default=2)
    a = p.parse_args()
    result = BenchResult(
        "view_overhead",
        "the qbot navigation launch as fast as possible, headless and with the view "
        "recording (--save-html, no browser), alternated",
    )
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        subprocess.run(
            [
                sys.executable,
                "-m",
                "twil_control.tools.rasterize",
                str(ROOT / "sim/worlds/house.sdf"),
                "-o",
                str(tmp / "house"),
            ],
            check=True,
            capture_output=True,
        )
        # Two goals there and back keep the robot, the planner and every layer busy for the whole run.
        base = [
            str(ROOT / "launch/qbot_navigation.launch.yaml"),
            "slam:=false",
            f"map:={tmp / 'house.yaml'}",
            "goal:=2 0 0; 0 0 3.14; 2 0 0; 0 0 3.14",
            "--duration",
            str(a.duration),
            "--no-bag",
        ]
        walls = {"headless": [], "view": []}
        for k in range(a.repeats):
            sim, wall = run(base, tmp)
            walls["headless"].append(wall)
            sim_v, wall_v = run(base + ["--save-html", str(tmp / f"run{k}.html")], tmp)
            walls["view"].append(wall_v)
            size = (tmp / f"run{k}.html").stat().st_size
            print(
                f"repeat {k}: headless {sim:.1f} s sim in {wall:.2f} s; view {sim_v:.1f} s sim in {wall_v:.2f} s "
                f"(HTML {size / 1e6:.2f} MB)"
            )
        h, v = statistics.median(walls["headless"]), statistics.median(walls["view"])
        print(
            f"median wall: headless {h:.2f} s, view {v:.2f} s: the view costs {100 * (v / h - 1):+.0f}% "
            f"(real-time factor headless {sim / h:.2f}, with the view {sim_v / v:.2f})"
        )
        result.add("headless_wall_s", h, "s (median)")
        result.add("view_wall_s", v, "s (median)")
        result.add(
            "view_cost_percent",
            100 * (v / h - 1),
            "% more wall time",
            headline="view recording, extra wall time",
        )
        result.add("html_mb", size / 1e6, "MB")
        result.write()


if __name__ == "__main__":
    main()
