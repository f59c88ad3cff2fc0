"""A reference trajectory for the cart_linearizing_controller (the lab's reference publisher).

Node type ``twil_control/cart_reference``. Reads a program of segments from YAML and publishes
twil_control/CartLinearizingCommand at ``rate`` Hz: the platform's goal pose of the current
segment, and the arm on a quintic (minimum-jerk, rest-to-rest) path from where the previous
segment left it (the first segment starts from the arm's measured position on
``joint_states``) to the segment's ``arm_positions`` in ``arm_duration`` seconds, with its
velocities and accelerations. Each command is stamped with the time of its sample: the
controller holds it to second order until the next one (control/trajectory.py), so 100 Hz
commands track like 1 kHz ones.

Program file: a list of ``{time: s, platform_pose: {x, y, theta}, arm_positions: [7],
arm_duration: s}``; ``time`` >= 0 and increasing; ``arm_duration`` > 0 (default 3 s).

Private params: ``file`` (required; a relative path: the working directory, then the package
root, core.paths), ``topic`` (cart_linearizing_controller/command),
``rate`` (100 Hz), ``joint_states`` (/joint_states), ``arm_joints`` (wam_joint_1..7),
``goal`` ("": as in the file; "x y theta": every segment's platform pose replaced, the launch
file's ``goal:=`` argument).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..control.trajectory import quintic
from ..core.messages import header, msg_class
from ..core.paths import InputPathError, find_file
from ..core.yaml_io import YamlError, display_path, load_yaml
from .base import RosNode

COMMAND_TYPE = "twil_control/CartLinearizingCommand"


class CartReferenceError(ValueError):
    """A reference program that cannot be followed; the message names the file and entry."""


@dataclass
class CartReferenceParams:
    file: str
    topic: str = "cart_linearizing_controller/command"
    rate: float = 100.0
    joint_states: str = "/joint_states"
    arm_joints: list[str] = field(default_factory=lambda: [f"wam_joint_{i}" for i in range(1, 8)])
    goal: str = ""


@dataclass
class Segment:
    time: float
    pose: tuple[float, float, float]
    arm: np.ndarray
    duration: float


def parse_goal(text: str, where: str) -> tuple[float, float, float] | None:
    """"x y theta" -> a pose; "" -> None."""
    if not text.strip():
        return None
    try:
        values = [float(v) for v in text.replace(",", " ").split()]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise CartReferenceError(f"{where}: goal must be three finite numbers \"x y theta\" (m, m, rad), "
                                 f"got {text!r}")
    return values[0], values[1], values[2]


def load_program(path: Path, n_arm: int, goal) -> list[Segment]:
    where = f"reference program {display_path(path)}"
    try:
        entries = load_yaml(path)
    except YamlError as error:
        raise CartReferenceError(f"reference program: {error}") from None
    if not isinstance(entries, list) or not entries:
        raise CartReferenceError(f"{where}: expected a non-empty list of segments")
    allowed = {"time", "platform_pose", "arm_positions", "arm_duration"}
    program, last = [], -math.inf
    for i, e in enumerate(entries):
        here = f"{where}: segment {i}"
        if not isinstance(e, dict) or set(e) - allowed or "time" not in e:
            raise CartReferenceError(f"{here} must be a mapping with keys {sorted(allowed)} ('time' required), "
                                     f"got {e!r}")
        t = e["time"]
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not (0 <= t < math.inf) or t <= last:
            raise CartReferenceError(f"{here}: time must be a number of seconds >= 0, increasing (got {t!r})")
        pose = e.get("platform_pose", {})
        if not isinstance(pose, dict) or set(pose) - {"x", "y", "theta"}:
            raise CartReferenceError(f"{here}: platform_pose must be {{x, y, theta}}, got {pose!r}")
        pose = tuple(float(pose.get(k, 0.0)) for k in ("x", "y", "theta")) if goal is None else goal
        arm = np.asarray(e.get("arm_positions", []), dtype=float)
        if arm.shape != (n_arm,) or not np.isfinite(arm).all():
            raise CartReferenceError(f"{here}: arm_positions must be {n_arm} finite numbers, got {e.get('arm_positions')!r}")
        duration = e.get("arm_duration", 3.0)
        if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not 0 < duration < math.inf:
            raise CartReferenceError(f"{here}: arm_duration must be > 0 s, got {duration!r}")
        if not all(math.isfinite(v) for v in pose):
            raise CartReferenceError(f"{here}: platform_pose must be finite, got {pose}")
        program.append(Segment(float(t), pose, arm, float(duration)))
        last = t
    return program


class CartReference(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.typed_params(CartReferenceParams)
        if not (math.isfinite(p.rate) and p.rate > 0):
            raise CartReferenceError(f"node {self.fqn}: rate must be > 0 Hz (got {p.rate!r})")
        try:
            path = find_file(p.file, "reference program")
        except InputPathError as error:
            raise CartReferenceError(f"node {self.fqn}: {error}") from None
        self.program = load_program(path, len(p.arm_joints), parse_goal(p.goal, f"node {self.fqn}"))
        self.params = p
        self.publisher = self.create_publisher(p.topic, COMMAND_TYPE)
        self._cls = msg_class(COMMAND_TYPE)
        self._pose_cls = msg_class("geometry_msgs/Pose2D")
        self._starts: list[np.ndarray | None] = [None] * len(self.program)
        self._measured: np.ndarray | None = None
        self._seq = 0
        self.create_subscription(p.joint_states, "sensor_msgs/JointState", self._joint_states)

    def _joint_states(self, msg) -> None:
        if self._measured is None:
            index = {n: i for i, n in enumerate(msg.name)}
            if all(j in index for j in self.params.arm_joints):
                self._measured = np.array([msg.position[index[j]] for j in self.params.arm_joints])

    def on_start(self) -> None:
        self.create_timer(1.0 / self.params.rate, lambda event: self.publish_at(self.now()))

    def sample(self, t: float):
        """(pose, q, qd, qdd) of the program at time t, or None before it starts."""
        k = max((i for i, s in enumerate(self.program) if s.time <= t + 1e-9), default=None)
        if k is None:
            return None
        if self._starts[k] is None:  # the arm starts where the previous segment had it
            if k == 0:
                if self._measured is None:
                    return None  # no joint state yet: nothing sensible to command
                self._starts[0] = self._measured
            else:
                prev = self.program[k - 1]
                if self._starts[k - 1] is None:
                    self.sample(prev.time)
                base = self._starts[k - 1] if self._starts[k - 1] is not None else prev.arm
                self._starts[k] = quintic(base, prev.arm, prev.duration, self.program[k].time - prev.time)[0]
        seg = self.program[k]
        q, qd, qdd = quintic(self._starts[k], seg.arm, seg.duration, t - seg.time)
        return seg.pose, q, qd, qdd

    def publish_at(self, t: float) -> None:
        sample = self.sample(t)
        if sample is None:
            return
        (x, y, theta), q, qd, qdd = sample
        self.publisher.publish(self._cls(header=header("", t, self._seq), platform_pose=self._pose_cls(x=x, y=y, theta=theta),
                                         arm_positions=q, arm_velocities=qd, arm_accelerations=qdd))
        self._seq += 1
