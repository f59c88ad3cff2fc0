"""robot_state_publisher/robot_state_publisher (ROS 1 Noetic), and joint_state_publisher's role.

robot_state_publisher: the URDF's fixed joints on /tf_static once, the moving joints named on
``joint_states`` on /tf, throttled per joint as ROS does; floating and planar joints come from
elsewhere (odometry, localisation). joint_state_publisher: every movable joint on
``joint_states`` from ``source_list``, ``zeros`` or 0. Parameters: docs/robots.md, "The ROS
graph"; ``tf_prefix`` is warned about and ignored (tf2 has no prefixes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from twil_control.errors import InputError

from ..control.transforms import urdf_joint_pose
from ..core.messages import header, msg_class, to_sec
from ..core.ros_node import RosNode
from ..core.tf import StaticTfBroadcaster, TfBroadcaster, transform_stamped
from ..description.urdf import RobotDescription, parse_urdf

_MOVING = ("revolute", "continuous", "prismatic")


def _description(node: RosNode) -> RobotDescription:
    """The URDF of ``robot_description``, searched upwards from the node's namespace."""
    parts = [p for p in node.namespace.split("/") if p]
    for depth in range(len(parts), -1, -1):
        key = "/" + "/".join(parts[:depth] + ["robot_description"])
        if node.master.params.has(key):
            text = node.master.params.get(key)
            if not isinstance(text, str):
                raise InputError(f"node {node.fqn}: {key} is not a URDF string")
            return parse_urdf(text, f"parameter {key}")
    raise InputError(
        f"node {node.fqn}: no robot_description parameter in {node.namespace} or above "
        f'(load the URDF with <param name="robot_description" command="xacro ..."/> '
        f"or textfile=...)"
    )


def _mimics(description: RobotDescription) -> dict[str, tuple[str, float, float]]:
    """mimic joint -> (leader, multiplier, offset), from the URDF's <mimic> elements."""
    found = {}
    root = description.root_element
    for el in root.findall("joint") if root is not None else []:
        mimic = el.find("mimic")
        if mimic is not None and mimic.get("joint"):
            found[el.get("name")] = (
                mimic.get("joint"),
                float(mimic.get("multiplier", 1.0)),
                float(mimic.get("offset", 0.0)),
            )
    return found


@dataclass
class RobotStatePublisherParams:
    ros_package: ClassVar[str] = "robot_state_publisher"
    publish_frequency: float = 50.0
    ignore_timestamp: bool = False
    use_tf_static: bool = True
    tf_prefix: str = ""

    def __post_init__(self) -> None:
        if not (self.publish_frequency > 0 and math.isfinite(self.publish_frequency)):
            raise InputError(f"publish_frequency must be > 0 Hz (got {self.publish_frequency})")


class RobotStatePublisher(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(RobotStatePublisherParams)
        if p.tf_prefix:
            self.log.warning(
                "tf_prefix %r is ignored: tf2 has no frame prefixes (rename the frames "
                "in the description instead)",
                p.tf_prefix,
            )
        if not p.use_tf_static:
            self.log.warning("use_tf_static false: fixed joints are still published once on /tf_static")
        self.description = d = _description(self)
        self.moving = {name: j for name, j in d.joints.items() if j.type in _MOVING}
        self._origins = {name: (j.xyz, j.origin_quaternion) for name, j in self.moving.items()}
        self.mimics = {m: v for m, v in _mimics(d).items() if m in self.moving}
        self.interval = 1.0 / p.publish_frequency
        self.last: dict[str, float] = {}
        self._tf = TfBroadcaster(self)
        self._static = StaticTfBroadcaster(self)
        self.create_subscription("joint_states", "sensor_msgs/JointState", self._on_joint_states)

    def on_start(self) -> None:
        now = self.now()
        fixed = [
            transform_stamped(
                j.parent, j.child, now, *urdf_joint_pose("fixed", j.xyz, j.origin_quaternion, j.axis, 0.0)
            )
            for j in self.description.joints.values()
            if j.type == "fixed"
        ]
        if fixed:
            self._static.send(*fixed)

    def _on_joint_states(self, msg) -> None:
        stamp = self.now() if self.params.ignore_timestamp else to_sec(msg.header.stamp)
        positions = {name: float(q) for name, q in zip(msg.name, msg.position) if name in self.moving}
        for mimic, (leader, multiplier, offset) in self.mimics.items():
            if leader in positions:
                positions[mimic] = multiplier * positions[leader] + offset
        if not positions:
            return
        if not self.params.ignore_timestamp:
            last = min(self.last.get(name, -math.inf) for name in positions)
            if stamp < last + self.interval - 1e-9:
                return
        transforms = []
        for name, q in positions.items():
            if not math.isfinite(q):
                self.log_once(40, f"nan-{name}", f"joint {name}: non-finite position {q}; not published")
                continue
            j = self.moving[name]
            pose = urdf_joint_pose(j.type, *self._origins[name], j.axis, q)
            transforms.append(transform_stamped(j.parent, j.child, stamp, *pose))
            self.last[name] = stamp
        if transforms:
            self._tf.send(*transforms)


@dataclass
class JointStatePublisherParams:
    ros_package: ClassVar[str] = "joint_state_publisher"
    rate: float = 10.0
    source_list: list[str] = field(default_factory=list)
    zeros: dict = field(default_factory=dict)
    use_gui: bool = False
    publish_default_positions: bool = True

    def __post_init__(self) -> None:
        if not (self.rate > 0 and math.isfinite(self.rate)):
            raise InputError(f"rate must be > 0 Hz (got {self.rate})")


class JointStatePublisher(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(JointStatePublisherParams)
        if p.use_gui:
            self.log.warning(
                "use_gui: there is no joint_state_publisher GUI here; default positions are published"
            )
        d = _description(self)
        self.mimics = _mimics(d)
        self.joints = [name for name, j in d.joints.items() if j.type in _MOVING and name not in self.mimics]
        self.positions = {name: self._default(d, name) for name in self.joints}
        self.received: set[str] = set()
        self._pub = self.create_publisher("joint_states", "sensor_msgs/JointState")
        self._msg = msg_class("sensor_msgs/JointState")
        for topic in p.source_list:
            self.create_subscription(topic, "sensor_msgs/JointState", self._on_source)

    def _default(self, d: RobotDescription, name: str) -> float:
        if name in self.params.zeros:
            return float(self.params.zeros[name])
        el = d.root_element.find(f"joint[@name='{name}']/limit")
        if el is not None and el.get("lower") is not None and el.get("upper") is not None:
            lower, upper = float(el.get("lower")), float(el.get("upper"))
            if not lower <= 0.0 <= upper:
                return 0.5 * (lower + upper)
        return 0.0

    def _on_source(self, msg) -> None:
        for name, q in zip(msg.name, msg.position):
            if name in self.positions:
                self.positions[name] = float(q)
                self.received.add(name)

    def on_start(self) -> None:
        self._publish(None)
        self.create_timer(1.0 / self.params.rate, self._publish)

    def _publish(self, _event) -> None:
        names = [n for n in self.joints if self.params.publish_default_positions or n in self.received]
        values = {n: self.positions[n] for n in names}
        for mimic, (leader, multiplier, offset) in self.mimics.items():
            if leader in values:
                values[mimic] = multiplier * values[leader] + offset
        self._pub.publish(
            self._msg(
                header=header("", self.now()),
                name=list(values),
                position=np.array(list(values.values()), dtype=float),
                velocity=np.zeros(0),
                effort=np.zeros(0),
            )
        )
