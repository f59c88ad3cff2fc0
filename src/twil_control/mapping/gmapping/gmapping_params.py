"""gmapping's parameters, with slam_gmapping's ROS names, as one typed schema.

The defaults are gmapping's own (slam_gmapping's documented defaults); config/gmapping.yaml
sets the values of the original qbot launch. The node loads this schema with
core.typed_params.load_typed, so a misspelt name is an error naming the file and the key; the
offline runner (gmapping.offline) builds it directly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from twil_control.errors import InputError

# gmapping has a parameter named `str`, which shadows the builtin inside the class body (and
# in the type hints resolved from it): string fields are annotated with this alias instead.
Text = str


@dataclass
class GMappingParams:
    ros_package: ClassVar[str] = "gmapping"
    # frames and ROS-side timing (used by the node only)
    base_frame: Text = "base_link"
    map_frame: Text = "map"
    odom_frame: Text = "odom"
    map_update_interval: float = 5.0  # s between /map publications
    transform_publish_period: float = 0.05  # s between map -> odom on /tf; 0 = never
    throttle_scans: int = 1  # process one scan in this many
    processing_latency: float = 0.0  # s an update takes to publish (this package's; node docs)
    occ_thresh: float = 0.25  # hits/visits above this -> occupied (100) in /map
    # sensor ranges
    maxUrange: float = 80.0  # beams are used up to this range (longer ones are cut, free only)
    maxRange: float = 80.0  # beams beyond this are ignored entirely (no return)
    # scan matcher (hill climbing on the score of the scan in the particle's map)
    sigma: float = 0.05  # score of a beam: exp(-d^2 / sigma), d = endpoint to matched cell
    kernelSize: int = 1  # search +-kernelSize cells around each endpoint (0, 1 or 2)
    lstep: float = 0.05  # initial translational step (m), halved at each refinement
    astep: float = 0.05  # initial angular step (rad)
    iterations: int = 5  # refinements (step halvings)
    lsigma: float = 0.075  # likelihood of a beam: -d^2 / lsigma (no match: -0.5 / lsigma)
    ogain: float = 3.0  # weights: exp((l - l_max) / (ogain * particles))
    lskip: int = 0  # use one beam in lskip + 1
    minimumScore: float = 0.0  # a match scoring at or below this keeps the odometry pose
    # motion model (odometry noise, standard deviations per unit of motion)
    srr: float = 0.1  # translation error from translation (m/m)
    srt: float = 0.2  # rotation error from translation (rad/m), as gmapping's code uses it
    str: float = 0.1  # translation error from rotation (m/rad), as gmapping's code uses it
    stt: float = 0.2  # rotation error from rotation (rad/rad)
    # update gating
    linearUpdate: float = 1.0  # m of travelled path before a scan is processed
    angularUpdate: float = 0.5  # rad of turning before a scan is processed
    temporalUpdate: float = -1.0  # s since the last processed scan; < 0 disables it
    resampleThreshold: float = 0.5  # resample when Neff / particles drops below this
    particles: int = 30
    # initial map bounds (grown as needed) and resolution
    xmin: float = -100.0
    ymin: float = -100.0
    xmax: float = 100.0
    ymax: float = 100.0
    delta: float = 0.05
    # likelihood sampling ranges: gmapping reads them but its update path never calls the
    # sampled likelihood (ScanMatcher::likelihood); accepted and checked here for the same
    # launch files, and likewise unused by the filter.
    llsamplerange: float = 0.01
    llsamplestep: float = 0.01
    lasamplerange: float = 0.005
    lasamplestep: float = 0.005

    def __post_init__(self) -> None:
        positive = (
            "sigma",
            "lsigma",
            "ogain",
            "delta",
            "maxUrange",
            "maxRange",
            "lstep",
            "astep",
            "llsamplestep",
            "lasamplestep",
        )
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"{name} must be a positive finite number (got {value})")
        nonneg = (
            "srr",
            "srt",
            "str",
            "stt",
            "linearUpdate",
            "angularUpdate",
            "llsamplerange",
            "lasamplerange",
            "map_update_interval",
            "transform_publish_period",
            "processing_latency",
        )
        for name in nonneg:
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise InputError(f"{name} must be a finite number >= 0 (got {value})")
        if self.particles < 1:
            raise InputError(f"particles must be >= 1 (got {self.particles})")
        if self.kernelSize not in (0, 1, 2):
            raise InputError(
                f"kernelSize must be 0, 1 or 2 cells (got {self.kernelSize}; gmapping's default is 1)"
            )
        if self.iterations < 0 or self.lskip < 0:
            raise InputError(f"iterations and lskip must be >= 0 (got {self.iterations}, {self.lskip})")
        if self.throttle_scans < 1:
            raise InputError(f"throttle_scans must be >= 1 (got {self.throttle_scans})")
        if not 0.0 <= self.resampleThreshold <= 1.0:
            raise InputError(f"resampleThreshold must be in [0, 1] (got {self.resampleThreshold})")
        if not 0.0 < self.occ_thresh < 1.0:
            raise InputError(f"occ_thresh must be in (0, 1) (got {self.occ_thresh})")
        if not (self.xmin < self.xmax and self.ymin < self.ymax):
            raise InputError(
                f"map bounds need xmin < xmax and ymin < ymax (got x {self.xmin}..{self.xmax}, "
                f"y {self.ymin}..{self.ymax})"
            )
        if self.maxUrange > self.maxRange:
            raise InputError(f"maxUrange ({self.maxUrange}) must not exceed maxRange ({self.maxRange})")
        if not math.isfinite(self.temporalUpdate):
            raise InputError(f"temporalUpdate must be finite (< 0 disables it; got {self.temporalUpdate})")
