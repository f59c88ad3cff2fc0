"""gazebo_ros_laser's role: a simulated planar laser (qbot's Hokuyo by default) publishing
sensor_msgs/LaserScan in simulated time.

Drake has no ray cast, so the node cuts the world at the sensor's height (world/laser_scene.py)
and casts the beams with a compiled kernel. Readings follow REP 117 (+inf no return, -inf closer
than range_min); the scan is instantaneous, every beam at its stamp, as gazebo_ros_laser reports
it. The parameters, their defaults and the static transform it publishes: docs/qbot.md, "The
laser".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twil_control.errors import InputError

from ..core.messages import header, msg_class
from ..core.ros_node import RosNode
from ..core.tf import StaticTfBroadcaster, transform_stamped
from ..mapping import raycast
from ..mapping.laser_model import LaserSpec, readings
from .model_param import model_instances

_SPEC = LaserSpec()


@dataclass
class LaserParams:
    model: str
    link: str = "base_laser"
    frame_name: str = "base_laser"
    topic: str = "laser/scan"
    # the beam, range and noise defaults are the laser model's (LaserSpec)
    samples: int = _SPEC.samples
    min_angle: float = _SPEC.min_angle
    max_angle: float = _SPEC.max_angle
    range_min: float = _SPEC.range_min
    range_max: float = _SPEC.range_max
    resolution: float = _SPEC.resolution
    update_rate: float = 30.0
    noise_stddev: float = _SPEC.noise_stddev
    parent_frame: str = "base_link"

    def __post_init__(self) -> None:
        if not (self.update_rate > 0 and math.isfinite(self.update_rate)):
            raise InputError(f"update_rate must be a positive number of Hz (got {self.update_rate})")
        _ = self.spec  # building the LaserSpec checks the beam, range and noise parameters

    @property
    def spec(self) -> LaserSpec:
        return LaserSpec(
            self.samples,
            self.min_angle,
            self.max_angle,
            self.range_min,
            self.range_max,
            self.resolution,
            self.noise_stddev,
        )


class LaserSensor:
    """The laser's work for a node (the twil_control/laser node, or the gazebo_ros_laser plugin
    in the simulator node): the scanner system, the static mount transform, the messages."""

    def __init__(self, node, params: LaserParams, offset=None, rng_key: str | None = None) -> None:
        self.node = node
        self.params = params
        self.spec = params.spec
        self.offset = offset  # the sensor's <pose> in its link: (x, y, z, roll, pitch, yaw)
        self._pub = node.create_publisher(params.topic, "sensor_msgs/LaserScan")
        self._static_tf = StaticTfBroadcaster(node) if params.parent_frame else None
        self._mount = None
        self._rng = node.master.rng(rng_key or node.fqn)
        self._msg = msg_class("sensor_msgs/LaserScan")
        self._seq = 0
        self.scanner = None

    def _body(self, sim, name: str):
        model_instances(self.node, sim, self.params.model)  # a model that is not one: its own error
        try:
            return sim.body(self.params.model, name)  # a nested model's link as nested::link
        except ValueError as error:
            raise InputError(f"node {self.node.fqn}: {error}") from None

    def build_systems(self, sim) -> None:
        from ..world.laser import LaserScanner, mount_transform

        p = self.params
        sensor = self._body(sim, p.link)
        if p.parent_frame:
            self._mount = mount_transform(sim.plant, self._body(sim, p.parent_frame), sensor)
        self.scanner = sim.add_system(
            LaserScanner(
                sim,
                sensor,
                model_instances(self.node, sim, p.model),
                1.0 / p.update_rate,
                self._publish,
                self.node.master.clock,
                self.offset,
            ),
            f"{self.node.fqn}/{p.model}/{p.link}/scanner",
        )

    def on_start(self) -> None:
        if self._static_tf is not None and self._mount is not None:
            self._static_tf.send(
                transform_stamped(
                    self.params.parent_frame, self.params.frame_name, self.node.now(), *self._mount
                )
            )

    def true_ranges(self, scan) -> np.ndarray:
        """Ranges of the scan's beams before the sensor model (+inf where nothing is hit)."""
        s = self.spec
        if getattr(scan, "upside_down", False):
            # beam i at sensor angle a_i points at world heading yaw - a_i: the fan from
            # -max_angle up, read backwards
            max_angle = s.min_angle + (s.samples - 1) * s.angle_increment
            return raycast.cast(
                scan.x,
                scan.y,
                scan.yaw,
                -max_angle,
                s.angle_increment,
                s.samples,
                scan.segments,
                scan.circles,
            )[::-1].copy()
        return raycast.cast(
            scan.x, scan.y, scan.yaw, s.min_angle, s.angle_increment, s.samples, scan.segments, scan.circles
        )

    def _publish(self, scan) -> None:
        s = self.spec
        ranges = readings(self.true_ranges(scan), s, self._rng)
        self._pub.publish(
            self._msg(
                header=header(self.params.frame_name, scan.t, self._seq),
                angle_min=s.min_angle,
                angle_max=s.max_angle,
                angle_increment=s.angle_increment,
                time_increment=0.0,
                scan_time=1.0 / self.params.update_rate,
                range_min=s.range_min,
                range_max=s.range_max,
                ranges=ranges,
                intensities=np.zeros(0, dtype=np.float32),
            )
        )
        self._seq += 1


class Laser(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(LaserParams)
        self.sensor = LaserSensor(self, self.params)
        self.spec = self.sensor.spec

    @property
    def scanner(self):
        return self.sensor.scanner

    def build_systems(self, sim) -> None:
        self.sensor.build_systems(sim)

    def on_start(self) -> None:
        self.sensor.on_start()

    def true_ranges(self, scan) -> np.ndarray:
        return self.sensor.true_ranges(scan)

    def _publish(self, scan) -> None:
        self.sensor._publish(scan)
