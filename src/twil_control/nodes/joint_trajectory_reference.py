"""A program of joint trajectories for a controller that takes trajectory_msgs/JointTrajectoryPoint
(the WAM's computed-torque controller).

Node type ``twil_control/joint_trajectory_reference``: segments on quintic (minimum-jerk) paths
sampled at ``rate``, each sample held to second order by the controller until the next;
``duration: 0`` is a step published once, as ``rostopic pub`` would. Program and parameters:
docs/computed_torque.md and docs/launch_files.md, "The project's own publishers".
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..control.trajectory import SegmentChain
from ..core.messages import msg_class
from .joint_program import ProgramNode, ProgramParams, program_path, read_entries, segment

COMMAND_TYPE = "trajectory_msgs/JointTrajectoryPoint"


@dataclass
class JointTrajectoryReferenceParams(ProgramParams):
    topic: str = "computed_torque_controller/command"
    joints: list[str] = field(default_factory=lambda: [f"wam_joint_{i}" for i in range(1, 8)])


def load_program(path, n: int) -> SegmentChain:
    entries = read_entries(path, {"time", "positions", "duration"})
    return SegmentChain(
        [
            segment(
                e, f"reference program {path}: segment {i}", n, "positions", "duration", 3.0, allow_step=True
            )
            for i, e in enumerate(entries)
        ]
    )


class JointTrajectoryReference(ProgramNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.typed_params(JointTrajectoryReferenceParams)
        self.params = p
        self.start_program(p, load_program(program_path(p.file), len(p.joints)), p.joints)
        self.publisher = self.create_publisher(p.topic, COMMAND_TYPE)
        self._cls = msg_class(COMMAND_TYPE)
        self._duration_cls = msg_class("builtin_interfaces/Duration")
        self._stepped: set[int] = set()

    def publish_at(self, t: float) -> None:
        sample = self.chain.sample(t)
        if sample is None:
            return
        k, q, qd, qdd = sample
        start, _, duration = self.chain.segments[k]
        if duration == 0.0:  # a step: once
            if k in self._stepped:
                return
            self._stepped.add(k)
            qd = qdd = qd[:0]
        elif t > start + duration + 0.5 * self._period:  # the segment's last sample (at rest) is out
            return
        elapsed = max(t - start, 0.0)
        sec = int(elapsed)
        self.publisher.publish(
            self._cls(
                positions=q,
                velocities=qd,
                accelerations=qdd,
                effort=q[:0],
                time_from_start=self._duration_cls(sec=sec, nanosec=int(round((elapsed - sec) * 1e9))),
            )
        )
