"""robot_localization's parameters (ekf_localization_node, ukf_localization_node), as it reads
them from the node's private namespace.

The filter's own settings are a typed schema (unknown names are one warning each, as the
package ignores them). The sensors are ``odomN``, ``poseN``, ``twistN`` and ``imuN`` (the topic),
each with ``_config`` (15 booleans in the state's order) and the options its kind reads;
numbering starts at 0 and stops at the first gap, as robot_localization's does (a sensor after
a gap is warned about and not read). Matrices are 225 numbers, row-major.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..core import names
from ..core.param_rules import param
from ..core.params import ParamError, param_error, source_prefix
from ..localization.kalman_state import STATE_SIZE

KINDS = ("odom", "pose", "twist", "imu")
_SENSOR_KEY = re.compile(r"^(odom|pose|twist|imu)(\d+)(?:_(.+))?$")
#: the options each kind of sensor reads, with their type: bool, float, int
OPTIONS: dict[str, dict[str, type]] = {
    "odom": {
        "config": list,
        "differential": bool,
        "relative": bool,
        "pose_use_child_frame": bool,
        "pose_rejection_threshold": float,
        "twist_rejection_threshold": float,
        "queue_size": int,
        "nodelay": bool,
    },
    "pose": {
        "config": list,
        "differential": bool,
        "relative": bool,
        "rejection_threshold": float,
        "queue_size": int,
        "nodelay": bool,
    },
    "twist": {"config": list, "rejection_threshold": float, "queue_size": int, "nodelay": bool},
    "imu": {
        "config": list,
        "differential": bool,
        "relative": bool,
        "pose_rejection_threshold": float,
        "twist_rejection_threshold": float,
        "linear_acceleration_rejection_threshold": float,
        "remove_gravitational_acceleration": bool,
        "queue_size": int,
        "nodelay": bool,
    },
}


@dataclass
class FilterParams:
    """The filter's settings (RosFilter::loadParams), with robot_localization's defaults."""

    ros_package: ClassVar[str] = "robot_localization"
    dynamic_keys: ClassVar[re.Pattern] = re.compile(r"^(odom|pose|twist|imu)\d+(_.*)?$")
    no_effect: ClassVar[dict] = {
        "debug": (False, "the filter's debug file is not written"),
        "smooth_lagged_data": (
            False,
            "messages reach the filter in time order here, so there is no lagged data to smooth",
        ),
        "reset_on_time_jump": (False, "simulated time never jumps back"),
    }

    frequency: float = param(30.0, gt=0)
    sensor_timeout: float | None = param(None, gt=0)
    two_d_mode: bool = False
    transform_time_offset: float = param(0.0, finite=True)
    transform_timeout: float = param(0.0, ge=0)
    print_diagnostics: bool = True
    debug: bool = False
    debug_out_file: str = "robot_localization_debug.txt"
    publish_tf: bool = True
    invert_tf: bool = False
    publish_acceleration: bool = False
    permit_corrected_publication: bool = False
    reset_on_time_jump: bool = False
    map_frame: str = "map"
    odom_frame: str = "odom"
    base_link_frame: str = "base_link"
    base_link_frame_output: str | None = None
    world_frame: str | None = None
    tf_prefix: str = ""
    smooth_lagged_data: bool = False
    history_length: float = 0.0
    predict_to_current_time: bool = False
    use_control: bool = False
    stamped_control: bool = False
    control_timeout: float | None = param(None, gt=0)
    control_config: list[bool] | None = None
    acceleration_limits: list[float] | None = None
    acceleration_gains: list[float] | None = None
    deceleration_limits: list[float] | None = None
    deceleration_gains: list[float] | None = None
    dynamic_process_noise_covariance: bool = False
    initial_state: list[float] | None = None
    disabled_at_startup: bool = False
    process_noise_covariance: list[float] | None = None
    initial_estimate_covariance: list[float] | None = None
    gravitational_acceleration: float = param(9.80665, finite=True)
    # ukf_localization_node's
    alpha: float = param(0.001, gt=0)
    kappa: float = param(0.0, finite=True)
    beta: float = param(2.0, finite=True)


@dataclass
class SensorParams:
    """One input: ``kind`` (odom, pose, twist, imu), its name (odom0) and topic."""

    kind: str
    name: str
    topic: str
    config: np.ndarray  # 15 booleans
    differential: bool = False
    relative: bool = False
    pose_use_child_frame: bool = False
    thresholds: dict[str, float] = field(default_factory=dict)  # pose / twist / acceleration
    remove_gravitational_acceleration: bool = False
    #: the update vectors of its pose, twist and acceleration parts (the node sets them)
    parts: tuple = ()

    def threshold(self, part: str) -> float:
        return self.thresholds.get(part, math.inf)


def _sensor_value(server, full: str, value, kind: type):
    ok = {
        bool: isinstance(value, bool),
        int: isinstance(value, int) and not isinstance(value, bool),
        float: isinstance(value, (int, float)) and not isinstance(value, bool),
        str: isinstance(value, str),
        list: isinstance(value, list),
    }[kind]
    if not ok:
        what = {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "a list"}
        raise param_error(server, full, f"must be {what[kind]}")
    return float(value) if kind is float else value


def _config(server, full: str, value) -> np.ndarray:
    if not isinstance(value, list) or not all(isinstance(v, bool) for v in value):
        raise param_error(
            server,
            full,
            f"must be a list of {STATE_SIZE} booleans (x, y, z, roll, pitch, yaw, their "
            "velocities, ax, ay, az)",
        )
    out = np.zeros(STATE_SIZE, dtype=bool)
    out[: min(len(value), STATE_SIZE)] = value[:STATE_SIZE]
    return out


def read_sensors(server, namespace: str, warn: Callable[[str], None]) -> tuple[list[SensorParams], set[str]]:
    """The sensors under `namespace` and the keys they account for (read or warned about)."""
    raw = server.get(namespace, {})
    grouped: dict[tuple[str, int], dict[str, str]] = {}
    for key in raw:
        match = _SENSOR_KEY.match(key)
        if match:
            kind, index, option = match.group(1), int(match.group(2)), match.group(3) or ""
            grouped.setdefault((kind, index), {})[option] = key
    sensors: list[SensorParams] = []
    for kind in KINDS:
        index = 0
        while (kind, index) in grouped and "" in grouped[(kind, index)]:
            sensors.append(_sensor(server, namespace, raw, kind, index, grouped[(kind, index)], warn))
            index += 1
        for (k, i), keys in sorted(grouped.items()):
            if k == kind and i >= index:
                full = names.join(namespace, sorted(keys.values())[0])
                warn(
                    f"{source_prefix(server.source_of(full))}sensor {kind}{i} is not read: "
                    f"robot_localization reads {kind}0, {kind}1, ... up to the first one missing "
                    f"({kind}{index})"
                )
    used = {key for keys in grouped.values() for key in keys.values()}
    return sensors, used


def _sensor(server, namespace: str, raw: dict, kind: str, index: int, keys: dict, warn) -> SensorParams:
    name = f"{kind}{index}"
    topic_key = names.join(namespace, name)
    topic = _sensor_value(server, topic_key, raw[name], str)
    options = OPTIONS[kind]
    values: dict[str, object] = {}
    for option, key in keys.items():
        if not option:
            continue
        full = names.join(namespace, key)
        if option not in options:
            allowed = ", ".join(f"{name}_{o}" for o in options)
            warn(
                f"{source_prefix(server.source_of(full))}unknown parameter {full!r} is ignored, as "
                f"robot_localization ignores parameters it does not read; {name} reads: {allowed}"
            )
            continue
        if option == "config":
            values[option] = _config(server, full, raw[key])
        else:
            values[option] = _sensor_value(server, full, raw[key], options[option])
            if option.endswith("threshold") and not values[option] >= 0:
                raise param_error(server, full, "must be a number >= 0")
    config = values.get("config")
    if config is None:
        raise ParamError(
            f"{source_prefix(server.source_of(topic_key))}sensor {topic_key!r} has no "
            f"{name}_config: robot_localization cannot read its update vector (15 booleans)"
        )
    differential = bool(values.get("differential", False))
    relative = bool(values.get("relative", False))
    if differential and relative:
        warn(f"Both {name}_differential and {name}_relative were set to true. Using differential mode.")
        relative = False
    thresholds = {}
    for option, part in (
        ("pose_rejection_threshold", "pose"),
        ("twist_rejection_threshold", "twist"),
        ("linear_acceleration_rejection_threshold", "acceleration"),
        ("rejection_threshold", kind),
    ):
        if option in values:
            thresholds[part] = float(values[option])
    return SensorParams(
        kind,
        name,
        topic,
        config,
        differential,
        relative,
        bool(values.get("pose_use_child_frame", False)),
        thresholds,
        bool(values.get("remove_gravitational_acceleration", False)),
    )


def matrix(server, full: str, values: list[float] | None, default: np.ndarray) -> np.ndarray:
    """A 15x15 matrix parameter (225 numbers, row-major), or `default` when unset."""
    if values is None:
        return default.copy()
    if len(values) != STATE_SIZE * STATE_SIZE or not all(math.isfinite(v) for v in values):
        raise param_error(server, full, f"must be {STATE_SIZE * STATE_SIZE} finite numbers (a 15x15 matrix)")
    return np.array(values, dtype=float).reshape(STATE_SIZE, STATE_SIZE)


def six(server, full: str, values, default: float, kind: type = float) -> np.ndarray:
    """A per-twist-variable parameter (6 values), `default` each when unset."""
    if values is None:
        return np.full(6, default, dtype=float if kind is float else bool)
    if len(values) != 6:
        raise param_error(server, full, "must have 6 entries (vx, vy, vz, vroll, vpitch, vyaw)")
    return np.array(values, dtype=float if kind is float else bool)
