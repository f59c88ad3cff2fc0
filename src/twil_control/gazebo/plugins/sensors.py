"""The sensor plugins: gazebo_ros_laser / gpu_laser, gazebo_ros_imu and gazebo_ros_imu_sensor,
hector_gazebo_ros_imu, gazebo_ros_p3d (docs/robots.md, "Plugins"; hector's: docs/ros1.md).

The IMU's acceleration is the change of the link's velocity since the previous sample over the
period: exact for the discrete plant sampled every step, the period's mean at lower rates.
Proper acceleration, so +9.81 up at rest. Noise and hector's error models draw from the run's
seed.
"""

from __future__ import annotations

import math

import numpy as np

from twil_control.errors import InputError

from ...control.transforms import qmul, qrot
from ...core.messages import header, msg_class
from ...core.odometry_msg import covariance, odometry_msg
from ..laser_node import LaserParams, LaserSensor
from . import PluginNode


def _body(sim, model: str, link: str, who: str):
    try:
        return sim.body(model, link)  # a nested model's link as nested::link
    except ValueError as error:
        raise InputError(f"{who}: {error}") from None


def _period(rate: float, sim) -> float:
    return 1.0 / rate if rate > 0 else sim.config.time_step


class LaserPlugin:
    def __init__(self, host, model: str, config) -> None:
        self.node = node = PluginNode(host, config.namespace)
        self.config = config
        if config.noise.mean or config.noise.bias_mean or config.noise.bias_stddev:
            node.log.warning(
                "laser of %s on %s: noise mean and bias are not simulated (stddev %.4g is)",
                model,
                config.link,
                config.noise.stddev,
            )
        self.params = LaserParams(
            model=model,
            link=config.link,
            frame_name=config.frame,
            topic=config.topic,
            samples=config.samples,
            min_angle=config.min_angle,
            max_angle=config.max_angle,
            range_min=config.range_min,
            range_max=config.range_max,
            resolution=config.range_resolution,
            update_rate=config.update_rate or 1000.0,
            noise_stddev=config.noise.stddev,
            parent_frame="",
        )
        self.sensor = LaserSensor(
            node, self.params, offset=config.pose, rng_key=f"{node.fqn}/{model}/{config.link}/laser"
        )

    def build_systems(self, sim) -> None:
        if not self.config.update_rate:
            self.params.update_rate = 1.0 / sim.config.time_step
        self.sensor.build_systems(sim)


class _Noise:
    """One sensor noise: N(mean, stddev²) per sample plus a bias drawn once (Gazebo's model)."""

    def __init__(self, rng: np.random.Generator, config, extra_stddev: float = 0.0) -> None:
        self.rng, self.mean = rng, config.mean
        self.stddev = math.hypot(config.stddev, extra_stddev)
        bias = rng.normal(config.bias_mean, config.bias_stddev) if config.bias_stddev else config.bias_mean
        self.bias = bias if rng.random() < 0.5 else -bias
        self.active = bool(self.stddev or self.mean or self.bias)

    def add(self, values: tuple) -> tuple:
        if not self.active:
            return values
        noise = self.rng.normal(self.mean, self.stddev, 3) if self.stddev else np.full(3, self.mean)
        return tuple(float(v + n + self.bias) for v, n in zip(values, noise))


class ImuPlugin:
    def __init__(self, host, model: str, config) -> None:
        self.node = node = PluginNode(host, config.namespace)
        self.config, self.model = config, model
        if any(config.xyz_offset) or any(config.rpy_offset):
            node.log.warning("IMU of %s on %s: xyzOffset / rpyOffset are not applied", model, config.link)
        rng = host.master.rng(f"{node.fqn}/{model}/{config.link}/imu")
        self.rate_noise = _Noise(rng, config.rate_noise, config.gaussian_noise)
        self.accel_noise = _Noise(rng, config.accel_noise, config.gaussian_noise)
        self._pub = node.create_publisher(config.topic, "sensor_msgs/Imu")
        self._msg = msg_class("sensor_msgs/Imu")
        self._vec = msg_class("geometry_msgs/Vector3")
        self._quat = msg_class("geometry_msgs/Quaternion")
        self._cov_rate = np.diag([self.rate_noise.stddev**2] * 3).reshape(9)
        self._cov_accel = np.diag([self.accel_noise.stddev**2] * 3).reshape(9)
        self._cov_orientation = np.zeros(9)
        self._previous = None
        self._seq = 0

    def build_systems(self, sim) -> None:
        from ...world.body_state import BodyStateReporter

        body = _body(sim, self.model, self.config.link, self.node.fqn)
        self.period = _period(self.config.update_rate, sim)
        g = sim.plant.gravity_field().gravity_vector()
        self.gravity = (float(g[0]), float(g[1]), float(g[2]))
        sim.add_system(
            BodyStateReporter(sim, body, self.period, self._report, self.node.master.clock),
            f"{self.node.fqn}/{self.model}/{self.config.link}/imu",
        )

    def _report(self, t, position, quat, v_body, w_body) -> None:
        v_world = qrot(quat, v_body)
        if self._previous is None:
            a_world = (0.0, 0.0, 0.0)
        else:
            a_world = tuple((a - b) / self.period for a, b in zip(v_world, self._previous))
        self._previous = v_world
        q_bw = (-quat[0], -quat[1], -quat[2], quat[3])
        proper = qrot(q_bw, tuple(a - g for a, g in zip(a_world, self.gravity)))
        rates = self.rate_noise.add(tuple(w_body))
        accel = self.accel_noise.add(proper)
        vec = self._vec
        self._pub.publish(
            self._msg(
                header=header(self.config.frame, t, self._seq),
                orientation=self._quat(x=quat[0], y=quat[1], z=quat[2], w=quat[3]),
                orientation_covariance=self._cov_orientation,
                angular_velocity=vec(x=rates[0], y=rates[1], z=rates[2]),
                angular_velocity_covariance=self._cov_rate,
                linear_acceleration=vec(x=accel[0], y=accel[1], z=accel[2]),
                linear_acceleration_covariance=self._cov_accel,
            )
        )
        self._seq += 1


class _ErrorModel:
    """hector's SensorModel: error = offset + drift + N(0, noise²); the drift moves by
    -dt (drift f + N(0, (sqrt(2 f) drift)²)) each update (hector_gazebo_plugins' sensor_model.h)."""

    def __init__(self, rng: np.random.Generator, model) -> None:
        self.rng = rng
        self.offset = np.array(model.offset, dtype=float)
        self.drift = np.array(model.drift, dtype=float)
        self.frequency = np.array(model.drift_frequency, dtype=float)
        self.noise = np.array(model.gaussian_noise, dtype=float)
        self.current_drift = np.zeros_like(self.offset)
        self.error = np.zeros_like(self.offset)

    def update(self, dt: float) -> np.ndarray:
        kick = self.rng.normal(0.0, 1.0, self.drift.shape) * np.sqrt(2.0 * self.frequency) * self.drift
        self.current_drift = self.current_drift - dt * (self.current_drift * self.frequency + kick)
        white = self.rng.normal(0.0, 1.0, self.noise.shape) * self.noise
        self.error = self.offset + self.current_drift + white
        return self.error


class HectorImuPlugin(ImuPlugin):
    def __init__(self, host, model: str, config) -> None:
        super().__init__(host, model, config)
        errors = config.hector
        rng = host.master.rng(f"{self.node.fqn}/{model}/{config.link}/hector_imu")
        self.accel_model = _ErrorModel(rng, errors.accel)
        self.rate_model = _ErrorModel(rng, errors.rate)
        self.heading_model = _ErrorModel(rng, errors.heading)
        self._cov_rate = np.diag(self.rate_model.noise**2).reshape(9)
        self._cov_accel = np.diag(self.accel_model.noise**2).reshape(9)

    def build_systems(self, sim) -> None:
        super().build_systems(sim)
        g = math.sqrt(sum(c * c for c in self.gravity))
        cov = np.zeros(9)
        cov[8] = float(self.heading_model.noise[0] ** 2)
        cov[0] = float(self.accel_model.noise[0] ** 2) / (g * g) if g > 0 else -1.0
        cov[4] = float(self.accel_model.noise[1] ** 2) / (g * g) if g > 0 else -1.0
        self._cov_orientation = cov

    def _report(self, t, position, quat, v_body, w_body) -> None:
        v_world = qrot(quat, v_body)
        if self._previous is None:
            a_world = (0.0, 0.0, 0.0)
        else:
            a_world = tuple((a - b) / self.period for a, b in zip(v_world, self._previous))
        self._previous = v_world
        q_bw = (-quat[0], -quat[1], -quat[2], quat[3])
        gravity_body = np.array(qrot(q_bw, self.gravity))
        proper = np.array(qrot(q_bw, a_world)) - gravity_body
        accel = proper + self.accel_model.update(self.period)
        rates = np.array(w_body, dtype=float) + self.rate_model.update(self.period)
        heading = float(self.heading_model.update(self.period)[0])
        orientation = qmul(
            qmul(_attitude_error(gravity_body, self.accel_model.error), quat), _yaw_quat(heading)
        )
        vec = self._vec
        self._pub.publish(
            self._msg(
                header=header(self.config.frame, t, self._seq),
                orientation=self._quat(
                    x=orientation[0], y=orientation[1], z=orientation[2], w=orientation[3]
                ),
                orientation_covariance=self._cov_orientation,
                angular_velocity=vec(x=float(rates[0]), y=float(rates[1]), z=float(rates[2])),
                angular_velocity_covariance=self._cov_rate,
                linear_acceleration=vec(x=float(accel[0]), y=float(accel[1]), z=float(accel[2])),
                linear_acceleration_covariance=self._cov_accel,
            )
        )
        self._seq += 1


def _yaw_quat(angle: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(angle / 2.0), math.cos(angle / 2.0))


def _attitude_error(gravity_body: np.ndarray, accel_error: np.ndarray) -> tuple[float, float, float, float]:
    """The tilt an accelerometer error gives an AHRS: the rotation from gravity to gravity plus
    the error, in the body frame (x, y, z, w)."""
    tilted = gravity_body + accel_error
    norm = float(np.linalg.norm(tilted) * np.linalg.norm(gravity_body))
    if norm == 0.0:
        return (0.0, 0.0, 0.0, 1.0)
    cos_alpha = float(tilted @ gravity_body) / norm
    axis = np.cross(gravity_body, accel_error) * math.sqrt(abs((1.0 - cos_alpha) / 2.0)) / norm
    return (float(axis[0]), float(axis[1]), float(axis[2]), math.sqrt(abs((1.0 + cos_alpha) / 2.0)))


class P3dPlugin:
    def __init__(self, host, model: str, config) -> None:
        self.node = node = PluginNode(host, config.namespace)
        self.config, self.model = config, model
        if config.frame not in ("world", "/world", "map", "/map"):
            node.log.warning(
                "p3d of %s: frameName %r: poses are given in the world frame", model, config.frame
            )
        if any(config.xyz_offset) or any(config.rpy_offset):
            node.log.warning("p3d of %s on %s: xyzOffsets / rpyOffsets are not applied", model, config.link)
        self._rng = host.master.rng(f"{node.fqn}/{model}/{config.link}/p3d")
        self._pub = node.create_publisher(config.topic, "nav_msgs/Odometry")
        self._cov = covariance([config.gaussian_noise**2] * 6)

    def build_systems(self, sim) -> None:
        from ...world.body_state import BodyStateReporter

        body = _body(sim, self.model, self.config.link, self.node.fqn)
        sim.add_system(
            BodyStateReporter(
                sim, body, _period(self.config.update_rate, sim), self._report, self.node.master.clock
            ),
            f"{self.node.fqn}/{self.model}/{self.config.link}/p3d",
        )

    def _report(self, t, position, quat, v_body, w_body) -> None:
        v_world, w_world = qrot(quat, v_body), qrot(quat, w_body)
        s = self.config.gaussian_noise
        if s:
            noise = self._rng.normal(0.0, s, 9)
            position = tuple(p + n for p, n in zip(position, noise[:3]))
            v_world = tuple(v + n for v, n in zip(v_world, noise[3:6]))
            w_world = tuple(w + n for w, n in zip(w_world, noise[6:]))
        self._pub.publish(
            odometry_msg(
                t,
                self.config.frame.lstrip("/"),
                self.config.link,
                position,
                quat,
                v_world,
                w_world,
                self._cov,
                self._cov,
            )
        )
