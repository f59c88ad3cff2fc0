"""Fakes for move_base on the bus (no Drake): a static map, a kinematic robot that integrates
cmd_vel and publishes map -> odom (identity) and odom -> base_link on /tf."""

from __future__ import annotations

import math

import numpy as np

from twil_control import PACKAGE_ROOT
from twil_control.control.transforms import quat_from_yaw
from twil_control.core import yaml_io  # noqa: F401  (params loading)
from twil_control.core.messages import header, msg_class
from twil_control.core.node import Master, Node
from twil_control.core.params import ParamServer
from twil_control.core.tf import StaticTfBroadcaster, TfBroadcaster, transform_stamped

FOOTPRINT = [[0.305, 0.199], [-0.305, 0.199], [-0.305, -0.199], [0.305, -0.199]]


def occupancy_grid(data: np.ndarray, resolution: float, origin=(0.0, 0.0)):
    h, w = data.shape
    info = msg_class("nav_msgs/MapMetaData")(
        map_load_time=header("", 0.0).stamp,
        resolution=resolution,
        width=w,
        height=h,
        origin=msg_class("geometry_msgs/Pose")(
            position=msg_class("geometry_msgs/Point")(x=origin[0], y=origin[1], z=0.0),
            orientation=msg_class("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
        ),
    )
    return msg_class("nav_msgs/OccupancyGrid")(
        header=header("map", 0.0), info=info, data=np.asarray(data, np.int8).ravel()
    )


class KinematicRobot(Node):
    """Integrates cmd_vel (unicycle) at `rate` Hz and publishes the tf tree map -> odom -> base_link.
    Records the commands it received."""

    def __init__(self, master: Master, pose=(0.0, 0.0, 0.0), rate: float = 50.0) -> None:
        super().__init__(master, "fake_robot")
        self.pose = np.array(pose, float)
        self.cmd = (0.0, 0.0)
        self.cmds: list[tuple[float, float, float]] = []
        self._tf = TfBroadcaster(self)
        StaticTfBroadcaster(self).send(transform_stamped("map", "odom", 0.0, (0, 0, 0), (0, 0, 0, 1)))
        self.create_subscription("/cmd_vel", "geometry_msgs/Twist", self._on_cmd)
        self._dt = 1.0 / rate
        self._publish()
        self.create_timer(self._dt, self._step)

    def _on_cmd(self, msg) -> None:
        self.cmd = (msg.linear.x, msg.angular.z)
        self.cmds.append((self.now(), *self.cmd))

    def _step(self, event) -> None:
        v, w = self.cmd
        x, y, th = self.pose
        self.pose = np.array(
            [x + v * math.cos(th) * self._dt, y + v * math.sin(th) * self._dt, th + w * self._dt]
        )
        self._publish()

    def _publish(self) -> None:
        x, y, th = self.pose
        self._tf.send(transform_stamped("odom", "base_link", self.now(), (x, y, 0.0), quat_from_yaw(th)))


def move_base_params(server: ParamServer, planner: str = "navfn/NavfnROS", **overrides) -> None:
    """The package's four parameter files in /move_base, as the launch file loads them."""
    cfg = PACKAGE_ROOT / "config"
    for ns in ("/move_base/global_costmap", "/move_base/local_costmap"):
        server.load_file(cfg / "costmap_common_params.yaml", ns)
    for f in (
        "global_costmap_params.yaml",
        "local_costmap_params.yaml",
        "base_local_planner_params.yaml",
        "move_base_params.yaml",
    ):
        server.load_file(cfg / f, "/move_base")
    server.set("/move_base/base_global_planner", planner)
    # no laser in these tests: the costmaps come from the static map alone
    for ns in ("global_costmap", "local_costmap"):
        server.set(f"/move_base/{ns}/observation_sources", "")
        server.delete(f"/move_base/{ns}/laser_scan_sensor")
    server.set("/move_base/local_costmap/static_map", True)
    for key, value in overrides.items():
        server.set(f"/move_base/{key}", value)
