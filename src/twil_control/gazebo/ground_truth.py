"""gazebo's p3d plugin role: the true pose and velocity of a body, for evaluation.

Publishes nav_msgs/Odometry on ~odom (`topic` param) and the transform frame_id -> child_frame_id
on /tf. The child frame is not base_link: base_link's parent is odom (wheel odometry), and a tf
frame has one parent, so the truth gets a frame of its own (base_link_ground_truth).
"""

from __future__ import annotations

from dataclasses import dataclass

from twil_control.errors import InputError

from ..core.odometry_msg import covariance, odometry_msg
from ..core.ros_node import RosNode
from ..core.tf import TfBroadcaster, transform_stamped
from .model_param import model_instances

_EXACT = covariance([0.0] * 6)  # ground truth: zero covariance


@dataclass
class GroundTruthParams:
    model: str  # spawned model name
    body_name: str = "base_link"
    frame_id: str = "world"
    child_frame_id: str = "base_link_ground_truth"
    update_rate: float = 100.0
    topic: str = "~odom"
    publish_tf: bool = True

    def __post_init__(self) -> None:
        if not self.update_rate > 0:
            raise InputError(f"update_rate must be > 0 Hz (got {self.update_rate})")


class GroundTruth(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(GroundTruthParams)
        self._pub = self.create_publisher(self.params.topic, "nav_msgs/Odometry")
        self._tf = TfBroadcaster(self) if self.params.publish_tf else None

    def build_systems(self, sim) -> None:
        from ..world.body_state import BodyStateReporter

        p = self.params
        instances = model_instances(self, sim, p.model)
        body = next(
            (
                sim.plant.GetBodyByName(p.body_name, i)
                for i in instances
                if sim.plant.HasBodyNamed(p.body_name, i)
            ),
            None,
        )
        if body is None:
            raise InputError(f"node {self.fqn}: model '{p.model}' has no body '{p.body_name}'")
        sim.add_system(
            BodyStateReporter(sim, body, 1.0 / p.update_rate, self._publish, self.master.clock),
            f"{self.fqn}/reporter",
        )

    def _publish(self, t, position, quaternion, v_body, w_body) -> None:
        p = self.params
        self._pub.publish(
            odometry_msg(
                t, p.frame_id, p.child_frame_id, position, quaternion, v_body, w_body, _EXACT, _EXACT
            )
        )
        if self._tf is not None:
            self._tf.send(transform_stamped(p.frame_id, p.child_frame_id, t, position, quaternion))
