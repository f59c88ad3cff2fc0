"""A timed geometry_msgs/Twist sequence for qbot's cmd_vel (a scripted teleop).

The current segment's command is published again at the file's ``rate``, because the drive
controller brakes after cmd_vel_timeout without one; ``stop: true`` goes silent and lets that
timeout brake. The file's format: docs/launch_files.md, "The project's own publishers". Errors
name the file and line of the bad parameter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from twil_control.errors import InputError

from ..core.messages import msg_class
from ..core.params import ParamServer
from ..core.ros_node import RosNode
from ..core.typed_params import load_typed


@dataclass
class Segment:
    time: float
    linear_x: float = 0.0
    angular_z: float = 0.0
    stop: bool = False


@dataclass
class CmdSequence:
    segments: list[Segment] = field(default_factory=list)
    rate: float = 20.0

    def __post_init__(self) -> None:
        if not (self.rate > 0 and math.isfinite(self.rate)):
            raise InputError(f"rate must be a positive number of Hz (got {self.rate})")
        times = [s.time for s in self.segments]
        if any(b <= a for a, b in zip(times, times[1:])) or any(t < 0 for t in times):
            raise InputError(f"segment times must be >= 0 and increasing (got {times})")


@dataclass
class CmdSequenceParams:
    file: str
    topic: str = "/qbot/cmd_vel"


def load_sequence(path: str) -> CmdSequence:
    server = ParamServer()
    server.load_file(path, "/sequence")
    return load_typed(server, "/sequence", CmdSequence)


class QbotCmdSequence(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(CmdSequenceParams)
        self.sequence = load_sequence(self.params.file)
        self._pub = self.create_publisher(self.params.topic, "geometry_msgs/Twist")
        self._twist = msg_class("geometry_msgs/Twist")
        self._vec = msg_class("geometry_msgs/Vector3")

    def on_start(self) -> None:
        self._tick(None)
        self.create_timer(1.0 / self.sequence.rate, self._tick)

    def current(self, t: float) -> Segment | None:
        active = [s for s in self.sequence.segments if s.time <= t + 1e-9]
        return active[-1] if active else None

    def _tick(self, event) -> None:
        seg = self.current(self.now())
        if seg is None or seg.stop:
            return
        self._pub.publish(
            self._twist(
                linear=self._vec(x=float(seg.linear_x), y=0.0, z=0.0),
                angular=self._vec(x=0.0, y=0.0, z=float(seg.angular_z)),
            )
        )
