"""A reference trajectory for the cart_linearizing_controller (the lab's reference publisher).

Node type ``twil_control/cart_reference``: a YAML program of platform poses and arm positions
(docs/cart_controller.md), the arm on quintic (minimum-jerk) paths from where the previous
segment left it, each command stamped with its sample's time, so that the controller's
second-order hold makes 100 Hz commands track like 1 kHz ones. Parameters:
docs/launch_files.md, "The project's own publishers".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..control.trajectory import SegmentChain
from ..core.messages import header, msg_class
from .joint_program import ProgramError, ProgramNode, ProgramParams, program_path, read_entries, segment

COMMAND_TYPE = "twil_control/CartLinearizingCommand"
CartReferenceError = ProgramError


@dataclass
class CartReferenceParams(ProgramParams):
    topic: str = "cart_linearizing_controller/command"
    arm_joints: list[str] = field(default_factory=lambda: [f"wam_joint_{i}" for i in range(1, 8)])
    goal: str = ""


def parse_goal(text: str, where: str) -> tuple[float, float, float] | None:
    """ "x y theta" -> a pose; "" -> None."""
    if not text.strip():
        return None
    try:
        values = [float(v) for v in text.replace(",", " ").split()]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise CartReferenceError(
            f'{where}: goal must be three finite numbers "x y theta" (m, m, rad), got {text!r}'
        )
    return values[0], values[1], values[2]


def load_program(path, n_arm: int, goal) -> tuple[list[tuple[float, float, float]], SegmentChain]:
    """(the platform pose of every segment, the arm's segment chain) of a program file."""
    entries = read_entries(path, {"time", "platform_pose", "arm_positions", "arm_duration"})
    poses, segments = [], []
    for i, e in enumerate(entries):
        here = f"reference program {path}: segment {i}"
        pose = e.get("platform_pose", {})
        if not isinstance(pose, dict) or set(pose) - {"x", "y", "theta"}:
            raise CartReferenceError(f"{here}: platform_pose must be {{x, y, theta}}, got {pose!r}")
        pose = tuple(float(pose.get(k, 0.0)) for k in ("x", "y", "theta")) if goal is None else goal
        if not all(math.isfinite(v) for v in pose):
            raise CartReferenceError(f"{here}: platform_pose must be finite, got {pose}")
        segments.append(segment(e, here, n_arm, "arm_positions", "arm_duration", 3.0, allow_step=False))
        poses.append(pose)
    return poses, SegmentChain(segments)


class CartReference(ProgramNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.typed_params(CartReferenceParams)
        self.params = p
        self.poses, chain = load_program(
            program_path(p.file), len(p.arm_joints), parse_goal(p.goal, f"node {self.fqn}")
        )
        self.start_program(p, chain, p.arm_joints)
        self.publisher = self.create_publisher(p.topic, COMMAND_TYPE)
        self._cls = msg_class(COMMAND_TYPE)
        self._pose_cls = msg_class("geometry_msgs/Pose2D")
        self._seq = 0

    def sample(self, t: float):
        """(pose, q, qd, qdd) of the program at time t, or None before it starts (or before a
        joint state gave the arm's start)."""
        sample = self.chain.sample(t)
        if sample is None:
            return None
        k, q, qd, qdd = sample
        return self.poses[k], q, qd, qdd

    def publish_at(self, t: float) -> None:
        sample = self.sample(t)
        if sample is None:
            return
        (x, y, theta), q, qd, qdd = sample
        self.publisher.publish(
            self._cls(
                header=header("", t, self._seq),
                platform_pose=self._pose_cls(x=x, y=y, theta=theta),
                arm_positions=q,
                arm_velocities=qd,
                arm_accelerations=qdd,
            )
        )
        self._seq += 1
