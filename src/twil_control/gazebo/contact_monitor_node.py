"""A bumper for evaluation (node type twil_control/contact_monitor): the simulator's contacts of a
robot with anything but the ground.

Publishes, at `update_rate` while contacts last, std_msgs/String on ~collisions (`topic`) with
one "robot_body -> other_model::body" line per contact pair (bodies named
"model::body"), and one empty message at start (the monitor ran); silent otherwise, so a run's
collision samples are its non-empty messages.
Private params: ``model`` (the spawned robot), ``ground`` (world models the robot may touch:
the floor its wheels stand on), ``update_rate`` (Hz).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

from twil_control.errors import InputError

from ..core.messages import msg_class
from ..core.ros_node import RosNode
from .model_param import watch_contacts


@dataclass
class ContactMonitorParams:
    model: str
    ground: list[str] = field(default_factory=lambda: ["floor", "ground_plane"])
    update_rate: float = 100.0
    topic: str = "~collisions"

    def __post_init__(self) -> None:
        if not self.update_rate > 0:
            raise InputError(f"update_rate must be > 0 Hz (got {self.update_rate})")


class ContactMonitor(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(ContactMonitorParams)
        # latched: the empty start message reaches the recorder, which subscribes after on_start
        self._pub = self.create_publisher(self.params.topic, "std_msgs/String", latch=True)
        self.count = 0  # samples with a collision

    def build_systems(self, sim) -> None:
        watch_contacts(self, sim, "monitor")

    def on_start(self) -> None:
        # one empty message: the bag shows the monitor ran, so no further message means no contact
        self._pub.publish(msg_class("std_msgs/String")(data=""))

    def _on_contacts(self, t: float, pairs) -> None:
        self.count += 1
        text = "\n".join(f"{a} -> {b}" for a, b in pairs)
        for a, b in pairs:
            self.log_once(logging.WARNING, f"contact-{a}-{b}", f"collision at t = {t:.3f} s: {a} touches {b}")
        self._pub.publish(msg_class("std_msgs/String")(data=text))
