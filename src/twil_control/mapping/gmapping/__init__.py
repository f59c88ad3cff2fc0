"""gmapping's Rao-Blackwellised particle filter SLAM (Grisetti, Stachniss, Burgard), written
for this project in numpy + numba: params (the ROS parameter schema), motion (odometry
sampling), grid (per-particle copy-on-write hit maps), matcher (scan matching, likelihood),
occupancy (the published map), filter (the particle filter), offline (feeding it directly)."""

from .filter import GMapping, Grid, ScanGeometry, ScanSizeError
from .gmapping_params import GMappingParams

__all__ = ["GMapping", "GMappingParams", "Grid", "ScanGeometry", "ScanSizeError"]
