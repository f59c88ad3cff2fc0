#!/usr/bin/env python3
"""The house world's ground-truth map (sim/worlds/house.sdf rasterised at 0.05 m) with one
simulated Hokuyo scan from the spawn pose drawn over it.

Run:  python docs/scripts/plot_house_map.py  [--out docs/img]
Writes docs/img/house_map.png. The map is what `python -m twil_control.tools.rasterize
sim/worlds/house.sdf -o house` writes; the scan is the laser's ray cast (no noise) of the same
shapes from (0, 0, yaw 0) at the qbot's scan height.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))
from twil_control.mapping import raycast  # noqa: E402
from twil_control.mapping.laser_model import LaserSpec  # noqa: E402
from twil_control.mapping.raster import default_extent, rasterize  # noqa: E402
from twil_control.tools.rasterize import QBOT_SCAN_HEIGHT  # noqa: E402
from twil_control.world.world_section import world_section  # noqa: E402

ROOMS = {
    "hall": (0.2, -1.6),
    "bedroom": (-3.2, 1.6),
    "kitchen": (-3.2, -1.0),
    "living": (3.5, 1.0),
    "bath": (3.2, -3.0),
    "study": (0.25, 4.0),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs/img")
    args = parser.parse_args()
    section = world_section(ROOT / "sim/worlds/house.sdf", QBOT_SCAN_HEIGHT)
    origin, size = default_extent(section, 0.05)
    grid = rasterize(section, 0.05, origin, size)
    spec = LaserSpec()
    ranges = raycast.cast(
        0.0, 0.0, 0.0, spec.min_angle, spec.angle_increment, spec.samples, section.segments(), section.circles
    )
    a = spec.angles()

    fig, ax = plt.subplots(figsize=(7, 7))
    extent = (origin[0], origin[0] + size[0], origin[1], origin[1] + size[1])
    ax.imshow(
        np.where(grid.data == 100, 0.0, 1.0),
        origin="lower",
        extent=extent,
        cmap="gray",
        vmin=0,
        vmax=1,
        interpolation="nearest",
    )
    ax.plot(
        ranges * np.cos(a),
        ranges * np.sin(a),
        ".",
        ms=2,
        color="tab:red",
        label="laser endpoints from (0, 0, yaw 0), 640 beams, 260°",
    )
    for i in range(0, spec.samples, 40):
        ax.plot(
            [0, ranges[i] * np.cos(a[i])], [0, ranges[i] * np.sin(a[i])], lw=0.4, color="tab:red", alpha=0.5
        )
    ax.plot(0, 0, "o", color="tab:blue", label="qbot spawn (0, 0)")
    for name, (x, y) in ROOMS.items():
        ax.text(x, y, name, ha="center", va="center", color="tab:blue", fontsize=10)
    occupied = np.count_nonzero(grid.data == 100)
    ax.set_title(
        f"house.sdf rasterised at z = {QBOT_SCAN_HEIGHT} m, 0.05 m cells "
        f"({grid.width} x {grid.height}, {occupied} occupied)",
        fontsize=10,
    )
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=1, fontsize=9)
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "house_map.png"
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
