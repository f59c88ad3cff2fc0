"""amcl's parameters, with amcl's ROS names and defaults (amcl_node.cpp, noetic), as one typed
schema. The node loads it with core.typed_params.load_typed (an unknown name is one warning, as
amcl ignores it); the bench builds it directly. Values amcl would crash on or loop forever with
(no particles, resample_interval 0, kld_err 0, a zero sigma) are refused with the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from twil_control.errors import InputError

ODOM_MODELS = ("diff", "omni", "diff-corrected", "omni-corrected")
LASER_MODELS = ("likelihood_field", "likelihood_field_prob", "beam")


@dataclass
class AmclParams:
    ros_package: ClassVar[str] = "amcl"
    # the map and the initial pose
    use_map_topic: bool = False
    first_map_only: bool = False
    initial_pose_x: float = 0.0
    initial_pose_y: float = 0.0
    initial_pose_a: float = 0.0
    initial_cov_xx: float = 0.5 * 0.5
    initial_cov_yy: float = 0.5 * 0.5
    initial_cov_aa: float = (math.pi / 12.0) ** 2
    # the filter
    min_particles: int = 100
    max_particles: int = 5000
    kld_err: float = 0.01
    kld_z: float = 0.99
    update_min_d: float = 0.2
    update_min_a: float = math.pi / 6.0
    resample_interval: int = 2
    selective_resampling: bool = False
    recovery_alpha_slow: float = 0.001
    recovery_alpha_fast: float = 0.1
    # the odometry model
    odom_model_type: str = "diff"
    odom_alpha1: float = 0.2
    odom_alpha2: float = 0.2
    odom_alpha3: float = 0.2
    odom_alpha4: float = 0.2
    odom_alpha5: float = 0.2
    # the laser model
    laser_model_type: str = "likelihood_field"
    laser_min_range: float = -1.0  # <= 0: the scan's range_min
    laser_max_range: float = -1.0  # <= 0: the scan's range_max
    laser_max_beams: int = 30
    laser_z_hit: float = 0.95
    laser_z_short: float = 0.1
    laser_z_max: float = 0.05
    laser_z_rand: float = 0.05
    laser_sigma_hit: float = 0.2
    laser_lambda_short: float = 0.1
    laser_likelihood_max_dist: float = 2.0
    do_beamskip: bool = False
    beam_skip_distance: float = 0.5
    beam_skip_threshold: float = 0.3
    beam_skip_error_threshold: float = 0.9
    # frames, tf and outputs
    odom_frame_id: str = "odom"
    base_frame_id: str = "base_link"
    global_frame_id: str = "map"
    transform_tolerance: float = 0.1
    tf_broadcast: bool = True
    force_update_after_initialpose: bool = False
    force_update_after_set_map: bool = False
    save_pose_rate: float = 0.5  # Hz: the estimate written back to ~initial_pose_* (<= 0: never)
    gui_publish_rate: float = -1.0  # read by amcl, unused there too (the cloud goes out every update)
    std_warn_level_x: float = 0.2
    std_warn_level_y: float = 0.2
    std_warn_level_yaw: float = 0.1
    bag_scan_period: float = -1.0  # amcl's --run-from-bag pacing; no bag mode here
    restore_defaults: bool = False  # dynamic_reconfigure's; no reconfigure server here

    def __post_init__(self) -> None:
        if self.min_particles < 1 or self.max_particles < 1:
            raise InputError(
                f"min_particles and max_particles must be >= 1 (got {self.min_particles}, {self.max_particles})"
            )
        if self.resample_interval < 1:
            raise InputError(
                f"resample_interval must be >= 1 update (got {self.resample_interval}; amcl divides by it)"
            )
        positive = ("kld_err", "laser_sigma_hit")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"{name} must be a finite number > 0 (got {value})")
        nonneg = (
            "odom_alpha1", "odom_alpha2", "odom_alpha3", "odom_alpha4", "odom_alpha5", "kld_z",
            "laser_z_hit", "laser_z_short", "laser_z_max", "laser_z_rand", "laser_lambda_short",
            "laser_likelihood_max_dist", "recovery_alpha_slow", "recovery_alpha_fast",
        )  # fmt: skip
        for name in nonneg:
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise InputError(f"{name} must be a finite number >= 0 (got {value})")
        finite = ("update_min_d", "update_min_a", "transform_tolerance", "laser_min_range", "laser_max_range")
        for name in finite:
            value = getattr(self, name)
            if not math.isfinite(value):
                raise InputError(f"{name} must be a finite number (got {value})")

    @property
    def alphas(self) -> tuple[float, float, float, float, float]:
        return (self.odom_alpha1, self.odom_alpha2, self.odom_alpha3, self.odom_alpha4, self.odom_alpha5)
