"""interactive_marker_twist_server's marker_server: rviz's drag-to-drive marker around the
robot, publishing geometry_msgs/Twist on ``~cmd_vel``.

The marker is driven from rviz; no rviz client connects to a run here, so the node advertises
its ``~cmd_vel`` (the topic husky_control's and jackal_control's twist_mux listen to), says so
in one info line and publishes nothing. Its parameters are read as the original reads them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..core.param_rules import param
from ..core.ros_node import RosNode


@dataclass
class MarkerServerParams:
    ros_package: ClassVar[str] = "interactive_marker_twist_server"
    link_name: str = "base_link"
    robot_name: str = "robot"
    marker_size_scale: float = param(1.0, gt=0)
    linear_scale: float | dict[str, float] = 1.0
    angular_scale: float | dict[str, float] = 2.2
    max_positive_linear_velocity: float | dict[str, float] = 1.0
    max_negative_linear_velocity: float | dict[str, float] = -1.0
    max_angular_velocity: float | dict[str, float] = 2.2


class MarkerServer(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(MarkerServerParams)
        self._pub = self.create_publisher("~cmd_vel", "geometry_msgs/Twist")
        self.log.info(
            "interactive marker for %s on %s: no rviz client in this run, so %s stays idle",
            self.params.robot_name,
            self.params.link_name,
            self.resolve("~cmd_vel"),
        )
