"""amcl's filter as amcl_node drives it on each laser scan (laserReceived), free of ROS: the node
looks up the odometry pose at the scan's stamp and the laser's mounting; this class decides
whether to update (amcl's per-axis motion test), runs the motion and laser models, resamples, and
reads out the estimate, the heaviest cluster's mean (docs/localization.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .amcl_laser import LaserData, LaserModel, LaserModelParams, prepare_ranges
from .amcl_map import AmclMap
from .amcl_odom import angle_diff, sample_motion
from .amcl_params import AmclParams
from .amcl_pf import ParticleFilter


@dataclass(frozen=True)
class Scan:
    """A LaserScan's numbers, its angles in the robot's frame (amcl transforms angle_min and
    angle_min + angle_increment through tf, so a laser mounted upside down works)."""

    ranges: np.ndarray  # as in the message (float32)
    range_min: float
    range_max: float
    angle_min: float  # in the robot's frame
    angle_increment: float  # in the robot's frame
    laser_x: float = 0.0  # the laser's position on the robot
    laser_y: float = 0.0


@dataclass(frozen=True)
class Estimate:
    pose: np.ndarray  # x, y, yaw (-pi, pi] in the global frame
    covariance: np.ndarray  # 36 values, geometry_msgs/PoseWithCovariance's layout
    weight: float  # the cluster's share of the particles' weight


@dataclass(frozen=True)
class Step:
    """What one scan did: `updated` (the laser model ran: publish the particle cloud),
    `resampled`, and the estimate to publish (after a resampling or the first scan)."""

    updated: bool = False
    resampled: bool = False
    estimate: Estimate | None = None
    skipped: str = ""  # why a scan was not used, when it was not


def laser_model_params(p: AmclParams) -> LaserModelParams:
    return LaserModelParams(
        p.laser_model_type, p.laser_max_beams, p.laser_z_hit, p.laser_z_short, p.laser_z_max,
        p.laser_z_rand, p.laser_sigma_hit, p.laser_lambda_short, p.laser_likelihood_max_dist,
        p.do_beamskip, p.beam_skip_distance, p.beam_skip_threshold, p.beam_skip_error_threshold,
    )  # fmt: skip


def initial_covariance(p: AmclParams) -> np.ndarray:
    return np.diag([p.initial_cov_xx, p.initial_cov_yy, p.initial_cov_aa])


class Amcl:
    """The filter on one map with one parameter set; `rng` is its only source of randomness."""

    def __init__(self, params: AmclParams, grid: AmclMap, rng: np.random.Generator) -> None:
        self.p, self.map, self.rng = params, grid, rng
        self.pf = ParticleFilter(
            min(params.min_particles, params.max_particles),
            params.max_particles,
            params.recovery_alpha_slow,
            params.recovery_alpha_fast,
            params.kld_err,
            params.kld_z,
            lambda n: grid.random_free_poses(rng, n),
            rng,
            params.selective_resampling,
        )
        self.laser = LaserModel(laser_model_params(params), grid)
        self.initialized = False  # amcl's pf_init_: the odometry pose of the last update is known
        self.odom_pose = np.zeros(3)  # at the last filter update
        self.force_update = False
        self._resample_count = 0
        self._laser_update: dict[str, bool] = {}
        self.set_pose(
            (params.initial_pose_x, params.initial_pose_y, params.initial_pose_a), initial_covariance(params)
        )

    # -- (re)initialisation ----------------------------------------------------------------
    def set_pose(self, mean, cov) -> None:
        """Particles drawn around `mean` (x, y, yaw) with covariance `cov` (3x3): the initial
        pose, /initialpose."""
        self.pf.init_gaussian(mean, cov)
        self.initialized = False

    def global_localization(self) -> None:
        """Particles spread uniformly over the map's free cells."""
        self.pf.init_uniform()
        self.initialized = False

    def request_nomotion_update(self) -> None:
        """The next scan updates the filter even if the robot has not moved."""
        self.force_update = True

    # -- one scan ----------------------------------------------------------------------------
    def process(self, odom_pose, scan: Scan, laser: str = "laser") -> Step:
        """One scan taken at odometry pose `odom_pose` (x, y, yaw in the odom frame) by the laser
        named `laser` (amcl keeps one update flag per laser frame)."""
        pose = np.asarray(odom_pose, dtype=float)
        flags = self._laser_update
        flags.setdefault(laser, True)
        if self.initialized:
            delta = (
                pose[0] - self.odom_pose[0],
                pose[1] - self.odom_pose[1],
                angle_diff(pose[2], self.odom_pose[2]),
            )
            p = self.p
            moved = (
                abs(delta[0]) > p.update_min_d
                or abs(delta[1]) > p.update_min_d
                or abs(delta[2]) > p.update_min_a
            )
            if moved or self.force_update:
                for name in flags:
                    flags[name] = True
            self.force_update = False
        first = not self.initialized
        if first:
            self.odom_pose = pose
            self.initialized = True
            for name in flags:
                flags[name] = True
            self._resample_count = 0
        elif flags[laser]:
            sample_motion(self.pf.poses, self.p.odom_model_type, delta, pose, self.p.alphas, self.rng)
        updated = resampled = False
        if flags[laser]:
            data = self._laser_data(scan)
            if data is None:
                return Step(skipped="range_max or range_min from the laser is negative")
            if self.p.laser_max_beams >= 2:  # amcl's UpdateSensor does nothing below 2 beams
                self.pf.update_sensor(lambda poses, w: self.laser.weigh(poses, w, data, self.pf.converged))
            flags[laser] = False
            updated = True
            self.odom_pose = pose
            self._resample_count += 1
            if self._resample_count % self.p.resample_interval == 0:
                self.pf.resample()
                resampled = True
        estimate = self.estimate() if (resampled or first) else None
        return Step(updated, resampled, estimate)

    def _laser_data(self, scan: Scan) -> LaserData | None:
        p = self.p
        range_max = float(
            np.float32(min(scan.range_max, p.laser_max_range) if p.laser_max_range > 0 else scan.range_max)
        )
        range_min = float(
            np.float32(max(scan.range_min, p.laser_min_range) if p.laser_min_range > 0 else scan.range_min)
        )
        if range_max <= 0.0 or range_min < 0.0:
            return None
        ranges = prepare_ranges(scan.ranges, range_min, range_max)
        bearings = scan.angle_min + np.arange(len(ranges)) * scan.angle_increment
        return LaserData(ranges, bearings, range_max, scan.laser_x, scan.laser_y)

    # -- the estimate ------------------------------------------------------------------------
    def estimate(self) -> Estimate | None:
        """The heaviest cluster's mean, with the whole set's covariance (amcl reports that)."""
        best = self.pf.best_cluster()
        if best is None:
            return None
        cov = np.zeros(36)
        cov[0], cov[1], cov[6], cov[7] = (
            self.pf.cov[0, 0],
            self.pf.cov[0, 1],
            self.pf.cov[1, 0],
            self.pf.cov[1, 1],
        )
        cov[35] = self.pf.cov[2, 2]
        return Estimate(best.mean.copy(), cov, best.weight)


def map_to_odom(map_pose, odom_pose) -> np.ndarray:
    """(x, y, yaw) of the odom frame in the map frame such that the robot at `odom_pose` in the
    odom frame is at `map_pose` in the map frame: map_pose * odom_pose^-1."""
    mx, my, ma = (float(v) for v in map_pose)
    ox, oy, oa = (float(v) for v in odom_pose)
    yaw = ma - oa
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array(
        [mx - (c * ox - s * oy), my - (s * ox + c * oy), math.atan2(math.sin(yaw), math.cos(yaw))]
    )
