"""What the clutter bench reads of the BARN benchmark (the-barn-challenge, MIT): a world's cylinders,
its path file (the metric's optimal path), Gazebo's DWA results (res/dwa_out.txt). From a
checkout (a folder holding jackal_helper/) or a bare git repository (read at a branch).
"""

from __future__ import annotations

import io
import math
import subprocess
from collections import defaultdict
from pathlib import Path

import numpy as np

BARN_RADIUS = 0.075
INIT = (-2.25, 3.0)  # run.py's INIT_POSITION for the static worlds
GOAL = (0.0, 10.0)  # relative to INIT


class BarnSource:
    def __init__(self, root: Path, branch: str = "main") -> None:
        self.root, self.branch = Path(root), branch
        if not (self.root / "jackal_helper").is_dir() and not (self.root / "HEAD").is_file():
            raise SystemExit(f"{root}: neither a the-barn-challenge checkout nor a git repository of it")

    def read(self, rel: str) -> bytes:
        if (self.root / "jackal_helper").is_dir():
            return (self.root / rel).read_bytes()
        return subprocess.run(
            ["git", "-C", str(self.root), "show", f"{self.branch}:{rel}"], capture_output=True, check=True
        ).stdout

    def world(self, index: int) -> str:
        return self.read(f"jackal_helper/worlds/BARN/world_{index}.world").decode()

    def path_length(self, index: int) -> float:
        """run.py's path length: start, the path file's cells in Gazebo coordinates, the goal."""
        cells = np.load(io.BytesIO(self.read(f"jackal_helper/worlds/BARN/path_files/path_{index}.npy")))
        r = BARN_RADIUS
        xy = np.column_stack([cells[:, 0] * 2 * r - r - 30 * r * 2, cells[:, 1] * 2 * r + r + 5])
        pts = np.vstack([INIT, xy, (INIT[0] + GOAL[0], INIT[1] + GOAL[1])])
        return float(np.hypot(*np.diff(pts, axis=0).T).sum())

    def dwa_rows(self) -> dict[int, list[tuple]]:
        """Gazebo's DWA runs per world: (success, collided, timeout, time, metric) as logged."""
        rows = defaultdict(list)
        for line in self.read("res/dwa_out.txt").decode().splitlines():
            w = line.split()
            if len(w) == 6:
                rows[int(w[0])].append((int(w[1]), int(w[2]), int(w[3]), float(w[4]), float(w[5])))
        return dict(rows)


def metric(success: bool, time_s: float, path_length: float) -> float:
    """run.py's navigation metric: success * optimal_time / clip(time, 2 optimal, 8 optimal),
    the optimal time at 2 m/s."""
    optimal = path_length / 2
    return float(success) * optimal / min(max(time_s, 2 * optimal), 8 * optimal) if optimal > 0 else math.nan
