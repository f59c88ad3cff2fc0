"""fake_localization's role: map -> odom on /tf such that map -> base_link is the simulator's
true pose (for navigating on a saved map without a localiser; SLAM runs publish map -> odom
themselves).

Subscribes to ``base_pose_ground_truth`` (nav_msgs/Odometry, the ground truth node's output;
remap it) and looks up odom -> base_link (wheel odometry) at the same time. Private params, as
fake_localization's: ``odom_frame_id`` (odom), ``base_frame_id`` (base_link),
``global_frame_id`` (map), ``delta_x``/``delta_y``/``delta_yaw`` (the map's offset from the
simulator's world frame).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from ..control import transforms as tr
from ..core.messages import to_sec
from ..core.ros_node import RosNode
from ..core.tf import TfBroadcaster, TfBuffer, TfError, transform_stamped


@dataclass
class FakeLocalizationParams:
    ros_package: ClassVar[str] = "fake_localization"
    odom_frame_id: str = "odom"
    base_frame_id: str = "base_link"
    global_frame_id: str = "map"
    delta_x: float = 0.0
    delta_y: float = 0.0
    delta_yaw: float = 0.0


class FakeLocalization(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(FakeLocalizationParams)
        self.tf = TfBuffer(self)
        self._br = TfBroadcaster(self)
        self.create_subscription("base_pose_ground_truth", "nav_msgs/Odometry", self._on_truth)

    def _on_truth(self, msg) -> None:
        p = self.params
        t = to_sec(msg.header.stamp)
        try:
            odom_base = self.tf.lookup_transform(p.odom_frame_id, p.base_frame_id)
        except TfError as exc:
            self.log_once(30, "no-odom", f"no {p.odom_frame_id} -> {p.base_frame_id} yet: {exc}")
            return
        pos, q = msg.pose.pose.position, msg.pose.pose.orientation
        # the truth in the map frame: world -> map offset (delta) applied
        yaw = tr.yaw_from_quat((q.x, q.y, q.z, q.w))
        c, s = math.cos(-p.delta_yaw), math.sin(-p.delta_yaw)
        dx, dy = pos.x - p.delta_x, pos.y - p.delta_y
        map_base = ((c * dx - s * dy, s * dx + c * dy, 0.0), tr.quat_from_yaw(yaw - p.delta_yaw))
        # planar: keep only x, y, yaw of odom -> base_link (the chassis pitches on its wheels)
        ob_t, ob_q = odom_base
        odom_base2d = ((ob_t[0], ob_t[1], 0.0), tr.quat_from_yaw(tr.yaw_from_quat(ob_q)))
        # plain-float composition (100 Hz): the same formulas as tr.compose / tr.inverse
        map_odom = tr.compose_floats(*map_base, *tr.inverse_floats(*odom_base2d))
        self._br.send(transform_stamped(p.global_frame_id, p.odom_frame_id, t, map_odom[0], map_odom[1]))
