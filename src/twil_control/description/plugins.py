"""The Gazebo plugins and sensors of a URDF, read with the parameter names and defaults of
gazebo_ros_pkgs (ROS 1 Noetic) into typed configurations the simulator's plugins run.

Supported (:data:`SUPPORTED`): gazebo_ros_control, the diff-drive and skid-steer drives, the
ray / gpu_ray laser, the IMU model plugin and IMU sensor plugin, hector_gazebo_plugins' IMU
(Husky's and Jackal's), p3d. Anything else gives one
warning naming the plugin's file and link and listing the supported ones; so does a tag of a
supported plugin that is not read (:func:`configure`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

from .urdf import DescriptionError, GazeboPlugin, GazeboSensor, RobotDescription, floats

__all__ = [
    "DriveConfig",
    "ImuConfig",
    "LaserConfig",
    "NoiseConfig",
    "P3dConfig",
    "RosControlConfig",
    "SUPPORTED",
    "configure",
]

ROS_CONTROL = "libgazebo_ros_control.so"
DIFF_DRIVE = "libgazebo_ros_diff_drive.so"
SKID_STEER = "libgazebo_ros_skid_steer_drive.so"
LASER = ("libgazebo_ros_laser.so", "libgazebo_ros_gpu_laser.so")
IMU = "libgazebo_ros_imu.so"
IMU_SENSOR = "libgazebo_ros_imu_sensor.so"
HECTOR_IMU = "libhector_gazebo_ros_imu.so"
P3D = "libgazebo_ros_p3d.so"
SUPPORTED = (ROS_CONTROL, DIFF_DRIVE, SKID_STEER, *LASER, IMU, IMU_SENSOR, HECTOR_IMU, P3D)

#: Tags every gazebo_ros plugin may carry that change nothing here.
_IGNORED = {
    "alwaysOn",
    "rosDebugLevel",
    "serviceName",
    "legacyModeNS",
    "robotParam",
    "robotSimType",
    "visualize",
}


@dataclass
class RosControlConfig:
    """libgazebo_ros_control.so: robotNamespace (default: the model's name), controlPeriod
    (default: the physics step), robotSimType (DefaultRobotHWSim only), robotParam (the URDF
    an SDF model's transmissions come from, searched upwards from robotNamespace)."""

    namespace: str
    control_period: float | None = None
    sim_type: str = "gazebo_ros_control/DefaultRobotHWSim"
    robot_param: str = "robot_description"  # the URDF whose <transmission>s it reads (an SDF model's)


@dataclass
class DriveConfig:
    """libgazebo_ros_diff_drive.so (2 joints) and libgazebo_ros_skid_steer_drive.so (4)."""

    kind: str  # "diff_drive" | "skid_steer"
    namespace: str
    left_joints: list[str]
    right_joints: list[str]
    wheel_separation: float
    wheel_diameter: float
    torque: float
    command_topic: str = "cmd_vel"
    odometry_topic: str = "odom"
    odometry_frame: str = "odom"
    robot_base_frame: str = "base_footprint"
    update_rate: float = 100.0
    wheel_acceleration: float = 0.0  # 0: no limit
    publish_tf: bool = True
    publish_wheel_tf: bool = False
    publish_wheel_joint_state: bool = False
    odometry_source: str = "world"  # world (ground truth, the plugins' default) | encoder
    legacy_mode: bool = False
    covariance: tuple[float, float, float] = (0.0001, 0.0001, 0.01)  # x, y, yaw (skid steer)


@dataclass
class NoiseConfig:
    """A Gaussian noise of a sensor: mean and stddev per sample, a bias drawn once."""

    mean: float = 0.0
    stddev: float = 0.0
    bias_mean: float = 0.0
    bias_stddev: float = 0.0


@dataclass
class LaserConfig:
    namespace: str
    link: str
    topic: str
    frame: str
    samples: int
    min_angle: float
    max_angle: float
    range_min: float
    range_max: float
    range_resolution: float
    update_rate: float
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    pose: tuple[float, ...] = (0.0,) * 6


@dataclass
class ImuConfig:
    namespace: str
    link: str
    topic: str
    frame: str
    update_rate: float  # Hz; 0 = every physics step
    gaussian_noise: float = 0.0  # the plugin's gaussianNoise (rates and accelerations)
    rate_noise: NoiseConfig = field(default_factory=NoiseConfig)  # <imu><angular_velocity>
    accel_noise: NoiseConfig = field(default_factory=NoiseConfig)  # <imu><linear_acceleration>
    xyz_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    hector: HectorErrors | None = None  # hector_gazebo_ros_imu's error models


@dataclass
class SensorErrorModel:
    """hector_gazebo_plugins' SensorModel: offset, a drift (first-order Gauss-Markov of
    ``drift`` stddev at ``drift_frequency``) and white noise; per axis for 3-vectors."""

    offset: tuple[float, ...] = (0.0, 0.0, 0.0)
    drift: tuple[float, ...] = (0.0, 0.0, 0.0)
    drift_frequency: tuple[float, ...] = (1.0 / 3600.0,) * 3
    gaussian_noise: tuple[float, ...] = (0.0, 0.0, 0.0)


@dataclass
class HectorErrors:
    accel: SensorErrorModel = field(default_factory=SensorErrorModel)
    rate: SensorErrorModel = field(default_factory=SensorErrorModel)
    heading: SensorErrorModel = field(
        default_factory=lambda: SensorErrorModel((0.0,), (0.0,), (1.0 / 3600.0,), (0.0,))
    )


@dataclass
class P3dConfig:
    namespace: str
    link: str
    topic: str
    frame: str = "world"
    update_rate: float = 0.0  # 0 = every physics step
    gaussian_noise: float = 0.0
    xyz_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass
class Configured:
    """What a description's <gazebo> elements amount to."""

    ros_control: list[RosControlConfig] = field(default_factory=list)
    drives: list[DriveConfig] = field(default_factory=list)
    lasers: list[LaserConfig] = field(default_factory=list)
    imus: list[ImuConfig] = field(default_factory=list)
    p3d: list[P3dConfig] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


class _Params:
    """A plugin's tags, read once each; the tags never read are warned about."""

    def __init__(self, plugin: GazeboPlugin, source: str) -> None:
        self.plugin, self.source = plugin, source
        self.unread = set(plugin.params) - _IGNORED

    def _what(self, tag: str) -> str:
        return f"{self.source}: {self.plugin.label()} <{tag}>"

    def text(self, tag: str, default: str | None = None, *aliases: str) -> str:
        for name in (tag, *aliases):
            self.unread.discard(name)
        for name in (tag, *aliases):
            if name in self.plugin.params:
                return self.plugin.params[name]
        if default is None:
            raise DescriptionError(f"{self._what(tag)} is required")
        return default

    def number(self, tag: str, default: float | None, *aliases: str, positive: bool = False) -> float:
        raw = self.text(tag, None if default is None else repr(default), *aliases)
        value = floats(raw, 1, self._what(tag))[0]
        if positive and not value > 0:
            raise DescriptionError(f"{self._what(tag)} must be > 0 (got {raw})")
        return value

    def flag(self, tag: str, default: bool, *aliases: str) -> bool:
        raw = self.text(tag, "true" if default else "false", *aliases).strip().lower()
        if raw not in ("true", "false", "1", "0"):
            raise DescriptionError(f"{self._what(tag)} must be true or false (got {raw!r})")
        return raw in ("true", "1")

    def vector(self, tag: str) -> tuple[float, float, float]:
        return floats(self.text(tag, "0 0 0"), 3, self._what(tag))

    def namespace(self, model: str, override: str | None) -> str:
        ns = self.text("robotNamespace", "")
        if override is not None:  # spawn_model -robot_namespace replaces it, as gazebo_ros does
            ns = override
        return "/" + ns.strip("/") if ns.strip("/") else "/"

    def leftover(self) -> str | None:
        if not self.unread:
            return None
        return (
            f"{self.source}: {self.plugin.label()}: tags {', '.join(sorted(self.unread))} are "
            f"not read here (see docs/robots.md); ignored"
        )


def configure(description: RobotDescription, model: str, robot_namespace: str | None = None) -> Configured:
    """Every plugin and sensor of ``description`` (spawned as ``model``) as a configuration, and
    the warnings for what is not supported."""
    out = Configured()
    source = description.source
    for plugin in description.plugins:
        params = _Params(plugin, source)
        if plugin.filename == ROS_CONTROL:
            ns = params.namespace(model, robot_namespace)
            if "robotNamespace" not in plugin.params and robot_namespace is None:
                ns = "/" + model  # gazebo_ros_control's default: the model's name
            period = params.number("controlPeriod", 0.0)
            sim_type = params.text("robotSimType", "gazebo_ros_control/DefaultRobotHWSim")
            if sim_type != "gazebo_ros_control/DefaultRobotHWSim":
                out.warnings.append(
                    f"{source}: {plugin.label()}: robotSimType {sim_type!r} is not "
                    f"available; DefaultRobotHWSim's behaviour is used"
                )
            robot_param = params.text("robotParam", "robot_description")
            out.ros_control.append(RosControlConfig(ns, period or None, sim_type, robot_param))
        elif plugin.filename in (DIFF_DRIVE, SKID_STEER):
            out.drives.append(_drive(params, plugin, model, robot_namespace, description))
        elif plugin.filename == IMU:
            ns = params.namespace(model, robot_namespace)
            link = params.text("bodyName")
            description.link(link, plugin.label())
            out.imus.append(
                ImuConfig(
                    ns,
                    link,
                    params.text("topicName", "imu"),
                    params.text("frameName", link),
                    params.number("updateRate", 0.0),
                    params.number("gaussianNoise", 0.0),
                    xyz_offset=params.vector("xyzOffset"),
                    rpy_offset=params.vector("rpyOffset"),
                )
            )
            if "imu" in plugin.params:
                params.unread.add("imu")
        elif plugin.filename == HECTOR_IMU:
            out.imus.append(_hector_imu(params, plugin, model, robot_namespace, description))
        elif plugin.filename == P3D:
            ns = params.namespace(model, robot_namespace)
            link = params.text("bodyName")
            description.link(link, plugin.label())
            out.p3d.append(
                P3dConfig(
                    ns,
                    link,
                    params.text("topicName"),
                    params.text("frameName", "world"),
                    params.number("updateRate", 0.0),
                    params.number("gaussianNoise", 0.0),
                    params.vector(
                        "xyzOffsets",
                    )
                    if "xyzOffsets" in plugin.params
                    else params.vector("xyzOffset"),
                    params.vector("rpyOffsets")
                    if "rpyOffsets" in plugin.params
                    else params.vector("rpyOffset"),
                )
            )
        else:
            out.warnings.append(_unsupported(plugin.label(), source, plugin.filename))
            continue
        if (note := params.leftover()) is not None:
            out.warnings.append(note)
    for sensor in description.sensors:
        _sensor(sensor, model, robot_namespace, description, out)
    return out


def _error_model(params: _Params, prefix: str, size: int) -> SensorErrorModel:
    def values(tag: str, default: float) -> tuple[float, ...]:
        raw = params.text(prefix + tag, repr(default))
        numbers = raw.split()
        count = size if len(numbers) != 1 else 1
        got = floats(raw, count, params._what(prefix + tag))
        return tuple(got) * size if count == 1 else tuple(got)

    return SensorErrorModel(
        values("Offset", 0.0),
        values("Drift", 0.0),
        values("DriftFrequency", 1.0 / 3600.0),
        values("GaussianNoise", 0.0),
    )


def _hector_imu(
    params: _Params, plugin: GazeboPlugin, model: str, override: str | None, description: RobotDescription
) -> ImuConfig:
    """hector_gazebo_ros_imu: bodyName, frameId (default: the body), topicName (imu), updateRate
    (0: every step), the accel/rate/heading error models, gaussianNoise for accel and rate,
    rpyOffset as accelerometer and heading offsets (the plugin's reading)."""
    ns = params.namespace(model, override)
    link = params.text("bodyName")
    description.link(link, plugin.label())
    errors = HectorErrors(
        _error_model(params, "accel", 3), _error_model(params, "rate", 3), _error_model(params, "heading", 1)
    )
    noise = params.number("gaussianNoise", 0.0)
    if noise:
        errors.accel.gaussian_noise = errors.rate.gaussian_noise = (noise,) * 3
    if "rpyOffset" in plugin.params:
        roll, pitch, yaw = params.vector("rpyOffset")
        ax, ay, az = errors.accel.offset
        errors.accel.offset = (ax or pitch * 9.8065, ay or -roll * 9.8065, az)
        if not errors.heading.offset[0] and yaw:
            errors.heading.offset = (yaw,)
    params.text("xyzOffset", "0 0 0")
    params.text("randomEngineSeed", "0")  # the run's --seed seeds every noise here
    return ImuConfig(
        ns,
        link,
        params.text("topicName", "imu"),
        params.text("frameId", link),
        params.number("updateRate", 0.0),
        hector=errors,
    )


def _unsupported(label: str, source: str, filename: str = "") -> str:
    found = _on_plugin_path(filename)
    if found is not None:  # Gazebo says "Failed to load plugin NAME" for a library it cannot load
        return (
            f"{source}: failed to load {label}: {found} (GAZEBO_PLUGIN_PATH) is a compiled Gazebo "
            f"plugin, which cannot run in this simulation; supported plugins: {', '.join(SUPPORTED)}"
        )
    return f"{source}: {label} is not supported and is not loaded; supported plugins: {', '.join(SUPPORTED)}"


def _on_plugin_path(filename: str):
    """The plugin library `filename` in a folder of GAZEBO_PLUGIN_PATH, or None."""
    import os
    from pathlib import Path

    for folder in os.environ.get("GAZEBO_PLUGIN_PATH", "").split(os.pathsep):
        if folder and filename and (Path(folder) / filename).is_file():
            return Path(folder) / filename
    return None


def _drive(
    params: _Params, plugin: GazeboPlugin, model: str, override: str | None, description: RobotDescription
) -> DriveConfig:
    ns = params.namespace(model, override)
    if plugin.filename == DIFF_DRIVE:
        left, right = [params.text("leftJoint", "left_joint")], [params.text("rightJoint", "right_joint")]
        separation = params.number("wheelSeparation", 0.34, positive=True)
        diameter = params.number("wheelDiameter", 0.15, positive=True)
        torque = params.number("wheelTorque", 5.0, positive=True)
        kind, tf_default = "diff_drive", True
    else:
        left = [
            params.text("leftFrontJoint", "left_front_joint"),
            params.text("leftRearJoint", "left_rear_joint"),
        ]
        right = [
            params.text("rightFrontJoint", "right_front_joint"),
            params.text("rightRearJoint", "right_rear_joint"),
        ]
        separation = params.number("wheelSeparation", 0.4, positive=True)
        diameter = params.number("wheelDiameter", 0.15, positive=True)
        torque = params.number("torque", 5.0, "wheelTorque", positive=True)
        kind, tf_default = "skid_steer", False
    for joint in left + right:
        description.joint(joint, plugin.label())
    source = params.text("odometrySource", "world").strip().lower()
    source = {"0": "encoder", "1": "world"}.get(source, source)
    if source not in ("world", "encoder"):
        raise DescriptionError(
            f"{description.source}: {plugin.label()} <odometrySource> must be "
            f"world or encoder (got {source!r})"
        )
    config = DriveConfig(
        kind,
        ns,
        left,
        right,
        separation,
        diameter,
        torque,
        command_topic=params.text("commandTopic", "cmd_vel"),
        odometry_topic=params.text("odometryTopic", "odom"),
        odometry_frame=params.text("odometryFrame", "odom"),
        robot_base_frame=params.text("robotBaseFrame", "base_footprint"),
        update_rate=params.number("updateRate", 100.0),
        wheel_acceleration=params.number("wheelAcceleration", 0.0) if kind == "diff_drive" else 0.0,
        publish_tf=params.flag("publishTf", tf_default, "broadcastTF", "publishOdomTF"),
        publish_wheel_tf=params.flag("publishWheelTF", False),
        publish_wheel_joint_state=params.flag("publishWheelJointState", False),
        odometry_source=source,
        legacy_mode=params.flag("legacyMode", kind == "diff_drive"),
        covariance=(
            params.number("covariance_x", 0.0001),
            params.number("covariance_y", 0.0001),
            params.number("covariance_yaw", 0.01),
        )
        if kind == "skid_steer"
        else (0.0, 0.0, 0.0),
    )
    if not math.isfinite(config.update_rate) or config.update_rate < 0:
        raise DescriptionError(f"{description.source}: {plugin.label()} <updateRate> must be >= 0")
    return config


def _find_float(element: ET.Element | None, path: str, default: float, what: str) -> float:
    if element is None:
        return default
    found = element.find(path)
    if found is None or not (found.text or "").strip():
        return default
    return floats(found.text, 1, f"{what} <{path}>")[0]


def _noise(element: ET.Element | None, what: str) -> NoiseConfig:
    if element is None:
        return NoiseConfig()
    kind = (element.findtext("type") or "gaussian").strip()
    if kind not in ("gaussian", "gaussian_quantized", "none"):
        raise DescriptionError(f"{what}: noise type {kind!r}: gaussian or none")
    if kind == "none":
        return NoiseConfig()
    return NoiseConfig(
        *(_find_float(element, tag, 0.0, what) for tag in ("mean", "stddev", "bias_mean", "bias_stddev"))
    )


def _sensor(
    sensor: GazeboSensor, model: str, override: str | None, description: RobotDescription, out: Configured
) -> None:
    source = description.source
    label = f"sensor {sensor.name!r} ({sensor.type}) on link {sensor.link}"
    if not sensor.link or sensor.link not in description.links:
        out.warnings.append(f'{source}: {label}: a sensor belongs in <gazebo reference="LINK">; not loaded')
        return
    el = sensor.element
    rate = _find_float(el, "update_rate", 0.0, f"{source}: {label}")
    pose = floats(el.findtext("pose"), 6, f"{source}: {label} <pose>", (0.0,) * 6)
    if not sensor.plugins:
        out.notes.append(
            f"{source}: {label} has no ROS plugin: Gazebo publishes it on its own "
            f"transport only, so nothing is simulated for it here"
        )
        return
    for plugin in sensor.plugins:
        params = _Params(plugin, source)
        ns = params.namespace(model, override)
        if sensor.type in ("ray", "gpu_ray") and plugin.filename in LASER:
            what = f"{source}: {label}"
            ray = el.find("ray")
            if ray is None:
                raise DescriptionError(f"{what}: a ray sensor needs <ray>")
            horizontal = ray.find("scan/horizontal")
            samples = int(_find_float(horizontal, "samples", 640, what))
            resolution = _find_float(horizontal, "resolution", 1.0, what)
            if resolution != 1.0:
                out.warnings.append(
                    f"{what}: <resolution> {resolution} (ranges interpolated or "
                    f"averaged between rays) is not simulated: one range per sample"
                )
            vertical = ray.find("scan/vertical")
            if vertical is not None and _find_float(vertical, "samples", 1, what) > 1:
                out.warnings.append(f"{what}: vertical samples are not simulated: one planar scan")
            noise = _noise(ray.find("noise"), what)
            out.lasers.append(
                LaserConfig(
                    ns,
                    sensor.link,
                    params.text("topicName", "/world"),
                    params.text("frameName", "/world").lstrip("/"),
                    samples,
                    _find_float(horizontal, "min_angle", 0.0, what),
                    _find_float(horizontal, "max_angle", 0.0, what),
                    _find_float(ray.find("range"), "min", 0.0, what),
                    _find_float(ray.find("range"), "max", 0.0, what),
                    _find_float(ray.find("range"), "resolution", 0.0, what),
                    rate,
                    noise,
                    pose,
                )
            )
            if params.text("gaussianNoise", "0") not in ("0", "0.0"):
                params.unread.add("gaussianNoise")
        elif sensor.type == "imu" and plugin.filename == IMU_SENSOR:
            what = f"{source}: {label}"
            imu = el.find("imu")

            def axis_noise(kind: str) -> NoiseConfig:
                return _noise(imu.find(f"{kind}/x/noise") if imu is not None else None, what)

            rate_hz = params.number("updateRateHZ", rate)
            out.imus.append(
                ImuConfig(
                    ns,
                    sensor.link,
                    params.text("topicName", "imu"),
                    params.text("frameName", sensor.link),
                    rate_hz,
                    params.number("gaussianNoise", 0.0),
                    axis_noise("angular_velocity"),
                    axis_noise("linear_acceleration"),
                    params.vector("xyzOffset"),
                    params.vector("rpyOffset"),
                )
            )
            params.text("bodyName", "")
        else:
            out.warnings.append(
                _unsupported(f"{label}'s plugin {plugin.name!r} ({plugin.filename})", source, plugin.filename)
            )
            continue
        if (note := params.leftover()) is not None:
            out.warnings.append(note)
