"""BARN's collision detector (node type jackal_helper/collision_publisher_node): std_msgs/Bool
``true`` on ``collision`` whenever the simulator's contacts hold a pair between the model
``jackal`` and anything but the ``ground_plane``, as jackal_helper's collision_publisher.cpp
publishes from Gazebo's contacts topic (one message per contacts message that holds such a
pair; nothing, never ``false``, otherwise).

The contacts are sampled every ``1 / update_rate`` s of simulated time (Gazebo publishes them
at every world update; 100 Hz here by default, two samples per 20 ms of the original's spin
loop). The original also subscribes to ``ground_truth/state`` to note an airborne robot, which
changes nothing it publishes: not replicated. Private params (this project's, optional):
``model`` (jackal), ``ground`` ([ground_plane]), ``update_rate`` (Hz).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

from ..core.messages import msg_class
from ..core.ros_node import RosNode
from ..errors import InputError
from .model_param import watch_contacts


@dataclass
class CollisionPublisherParams:
    model: str = "jackal"
    ground: list[str] = field(default_factory=lambda: ["ground_plane"])
    update_rate: float = 100.0

    def __post_init__(self) -> None:
        if not self.update_rate > 0:
            raise InputError(f"update_rate must be > 0 Hz (got {self.update_rate})")


class CollisionPublisher(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(CollisionPublisherParams)
        self._pub = self.create_publisher("collision", "std_msgs/Bool")
        self.count = 0  # messages published (samples with a contact)

    def build_systems(self, sim) -> None:
        watch_contacts(self, sim, "contacts")

    def _on_contacts(self, t: float, pairs) -> None:
        self.count += 1
        a, b = pairs[0]
        # the original logs "entity1:entity2" (model names) at every message, ROS_INFO
        self.log_once(logging.INFO, f"contact-{a}-{b}", f"{a.split('::')[0]}:{b.split('::')[0]}")
        self._pub.publish(msg_class("std_msgs/Bool")(data=True))
