"""The planar laser's measurement model: beam layout, noise, range resolution and the REP 117
encoding of readings out of range (pure numpy).

Beams span `min_angle` to `max_angle` inclusive, as sensor_msgs/LaserScan and Gazebo's ray sensor
lay them out. A reading above range_max is +inf, one below range_min -inf, nothing clamped, so a
consumer can tell the three cases apart (docs/slam.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twil_control.errors import InputError


@dataclass(frozen=True)
class LaserSpec:
    samples: int = 640
    min_angle: float = -2.26889
    max_angle: float = 2.26889
    range_min: float = 0.08
    range_max: float = 10.0
    resolution: float = 0.01
    noise_stddev: float = 0.0

    def __post_init__(self) -> None:
        if self.samples < 2:
            raise InputError(f"samples must be >= 2 (got {self.samples})")
        if not (
            math.isfinite(self.min_angle)
            and math.isfinite(self.max_angle)
            and self.min_angle < self.max_angle <= self.min_angle + 2 * math.pi + 1e-4
        ):
            # 1e-4 rad over a full turn: descriptions write 2 pi rounded up (6.28319)
            raise InputError(
                f"need min_angle < max_angle <= min_angle + 2 pi "
                f"(got min_angle {self.min_angle}, max_angle {self.max_angle})"
            )
        if not (0 <= self.range_min < self.range_max and math.isfinite(self.range_max)):
            raise InputError(
                f"need 0 <= range_min < range_max < inf (got range_min "
                f"{self.range_min}, range_max {self.range_max})"
            )
        if not (self.resolution >= 0 and math.isfinite(self.resolution)):
            raise InputError(f"resolution must be >= 0 m, 0 = no rounding (got {self.resolution})")
        if not (self.noise_stddev >= 0 and math.isfinite(self.noise_stddev)):
            raise InputError(f"noise_stddev must be >= 0 m, 0 = no noise (got {self.noise_stddev})")

    @property
    def angle_increment(self) -> float:
        return (self.max_angle - self.min_angle) / (self.samples - 1)

    def angles(self) -> np.ndarray:
        """Beam angles from the sensor's heading; the last one is exactly max_angle."""
        return np.linspace(self.min_angle, self.max_angle, self.samples)


def readings(true_ranges: np.ndarray, spec: LaserSpec, rng: np.random.Generator | None) -> np.ndarray:
    """float32 readings of a scan from its true ranges (docs/slam.md, "The laser")."""
    r = np.asarray(true_ranges, dtype=np.float64)
    if spec.noise_stddev > 0:
        if rng is None:
            raise InputError("a noisy laser needs a random generator")
        r = r + rng.normal(0.0, spec.noise_stddev, r.shape)  # a miss (+inf) stays +inf
    if spec.resolution > 0:
        r = np.round(r / spec.resolution) * spec.resolution
    r = np.where(r > spec.range_max, np.inf, np.where(r < spec.range_min, -np.inf, r))
    return r.astype(np.float32)
