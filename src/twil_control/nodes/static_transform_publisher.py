"""tf's static_transform_publisher: ``x y z yaw pitch roll frame_id child_frame_id [period_ms]``
(or with a quaternion ``x y z qx qy qz qw frame child``), published latched on /tf_static."""

from __future__ import annotations

from twil_control.errors import InputError

from ..control.transforms import quat_from_rpy, quat_normalized
from ..core.ros_node import NodeArgsError, RosNode
from ..core.tf import StaticTfBroadcaster, transform_stamped


class StaticTransformPublisher(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        args = self.args
        usage = (
            "x y z yaw pitch roll frame_id child_frame_id [period_in_ms] or "
            "x y z qx qy qz qw frame_id child_frame_id [period_in_ms]"
        )
        try:
            if len(args) in (8, 9) and not _is_number(args[6]):
                x, y, z, yaw, pitch, roll = map(float, args[:6])
                self.parent, self.child = args[6], args[7]
                self.quat = quat_from_rpy(roll, pitch, yaw)
            elif len(args) in (9, 10):
                x, y, z, qx, qy, qz, qw = map(float, args[:7])
                self.parent, self.child = args[7], args[8]
                self.quat = quat_normalized([qx, qy, qz, qw])
            else:
                raise InputError(f"expected {usage}")
        except ValueError as error:
            raise NodeArgsError(f"node {self.fqn}: bad args {' '.join(args)!r}: {error}") from None
        self.translation = (x, y, z)
        self._broadcaster = StaticTfBroadcaster(self)

    def on_start(self) -> None:
        self._broadcaster.send(
            transform_stamped(self.parent, self.child, self.now(), self.translation, self.quat)
        )


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False
