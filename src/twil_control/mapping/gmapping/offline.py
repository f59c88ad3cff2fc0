"""Running the filter over recorded scans and odometry directly (no bus, no tf): what the
CARMEN evaluation and the benchmarks use. The node (nodes/slam_gmapping.py) does the same
from LaserScan and tf messages."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .filter import GMapping, ScanGeometry
from .gmapping_params import GMappingParams


@dataclass
class OfflineRun:
    slam: GMapping
    scan_index: np.ndarray  # input index of every processed scan, in order
    poses: np.ndarray  # the best particle's final trajectory at those scans (k, 3)
    seconds: np.ndarray  # wall time of each processed scan


def run(
    ranges: np.ndarray,
    odom: np.ndarray,
    times: np.ndarray,
    geometry: ScanGeometry,
    params: GMappingParams,
    seed: int = 0,
    parallel: bool = False,
    progress=None,
) -> OfflineRun:
    """Feed every scan (with the odometry pose at its time) to a new filter."""
    slam = GMapping(params, geometry, np.random.default_rng(seed), parallel=parallel)
    used, seconds = [], []
    for k in range(len(ranges)):
        if slam.process(odom[k], ranges[k], float(times[k])):
            used.append(k)
            seconds.append(slam.last_process_seconds)
        if progress is not None:
            progress(k)
    scans, poses = slam.trajectory()
    return OfflineRun(slam, np.asarray(used, np.int64)[scans], poses, np.asarray(seconds))
