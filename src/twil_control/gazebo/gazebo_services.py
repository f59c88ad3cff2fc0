"""The simulator node's ROS interface, as gazebo_ros_api_plugin gives it in /gazebo.

/gazebo/model_states and link_states, set_model_state, and the services get_model_state,
set_model_state, reset_world, reset_simulation, (un)pause_physics, spawn_*_model and
delete_model, with gazebo_msgs' field names. Where they differ, and why (a state set applies at
the end of the current slice, time is never reset, pausing is refused because every node runs on
simulated time, the plant is fixed once time runs): docs/robots.md, "The ROS graph".
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

from ..core.messages import header, msg_class
from ..core.node import ServiceError
from ..core.odometry_msg import pose_msg, twist_msg

SERVICES = (
    "get_model_state",
    "set_model_state",
    "spawn_urdf_model",
    "spawn_sdf_model",
    "delete_model",
    "pause_physics",
    "unpause_physics",
    "reset_simulation",
    "reset_world",
)


@dataclass
class GetModelStateResponse:
    header: object = None
    pose: object = None
    twist: object = None
    success: bool = False
    status_message: str = ""


@dataclass
class StatusResponse:
    """SetModelState, SpawnModel and DeleteModel responses."""

    success: bool = False
    status_message: str = ""


@dataclass
class EmptyResponse:
    fields: dict = field(default_factory=dict)


class GazeboInterface:
    """The /gazebo topics and services of the simulator node `node` (the host of the plugins)."""

    def __init__(self, node, sim, rate: float) -> None:
        self.node, self.sim = node, sim
        self.pending: list = []  # state changes to apply between slices
        self._models = node.create_publisher("/gazebo/model_states", "gazebo_msgs/ModelStates")
        self._links = node.create_publisher("/gazebo/link_states", "gazebo_msgs/LinkStates")
        node.create_subscription(
            "/gazebo/set_model_state", "gazebo_msgs/ModelState", self._on_set_model_state
        )
        node.create_subscription("/gazebo/set_link_state", "gazebo_msgs/LinkState", self._on_set_link_state)
        for name in SERVICES:
            node.master.advertise_service(f"/gazebo/{name}", node.fqn, getattr(self, name))
        from ..world.model_states import BodyStates

        sim.add_system(
            BodyStates(sim, 1.0 / rate, self._publish, node.master.clock), f"{node.fqn}/body_states"
        )

    # -- topics ------------------------------------------------------------------------------
    def _publish(self, t, links, models) -> None:
        for pub, kind, states in (
            (self._links, "gazebo_msgs/LinkStates", links),
            (self._models, "gazebo_msgs/ModelStates", models),
        ):
            pub.publish(
                msg_class(kind)(
                    name=[s[0] for s in states],
                    pose=[pose_msg(s[1], s[2]) for s in states],
                    twist=[twist_msg(s[3], s[4]) for s in states],
                )
            )

    def _on_set_model_state(self, msg) -> None:
        self.set_model_state(model_state=msg)

    def _on_set_link_state(self, msg) -> None:
        self.node.log_once(
            logging.WARNING,
            "set_link_state",
            f"/gazebo/set_link_state ({msg.link_name}): a single link's state cannot be set "
            f"here; use /gazebo/set_model_state",
        )

    # -- services ----------------------------------------------------------------------------
    def get_model_state(self, model_name: str = "", relative_entity_name: str = "") -> GetModelStateResponse:
        from ..world.model_states import get_free_body_state

        if model_name not in self.sim.robots:
            return GetModelStateResponse(
                success=False,
                status_message=f"GetModelState: model [{model_name}] "
                f"does not exist (models: {', '.join(self.sim.robots)})",
            )
        if relative_entity_name not in ("", "world", "map"):
            return GetModelStateResponse(
                success=False, status_message="GetModelState: only poses relative to the world are supported"
            )
        position, quat, linear, angular = get_free_body_state(self.sim, model_name)
        return GetModelStateResponse(
            header(relative_entity_name or "world", self.node.now()),
            pose_msg(position, quat),
            twist_msg(linear, angular),
            True,
            "GetModelState: got properties",
        )

    def set_model_state(self, model_state=None) -> StatusResponse:
        name = getattr(model_state, "model_name", "")
        if name not in self.sim.robots:
            return StatusResponse(False, f"SetModelState: model [{name}] does not exist")
        frame = model_state.reference_frame
        if frame not in ("", "world", "map"):
            return StatusResponse(False, "SetModelState: only poses relative to the world are supported")
        p, o = model_state.pose.position, model_state.pose.orientation
        v, w = model_state.twist.linear, model_state.twist.angular
        self.pending.append(
            ("set", name, (p.x, p.y, p.z), (o.x, o.y, o.z, o.w), (v.x, v.y, v.z), (w.x, w.y, w.z))
        )
        return StatusResponse(True, "SetModelState: set model state done")

    def reset_world(self) -> EmptyResponse:
        self.pending.append(("reset",))
        return EmptyResponse()

    def reset_simulation(self) -> EmptyResponse:
        self.node.log.warning(
            "/gazebo/reset_simulation: models reset as reset_world does; simulated time is "
            "not reset (the run's clock and bag go on)"
        )
        return self.reset_world()

    def unpause_physics(self) -> EmptyResponse:
        return EmptyResponse()

    def pause_physics(self) -> EmptyResponse:
        raise ServiceError(
            "/gazebo/pause_physics is not supported: every node runs on simulated time, so a "
            "paused world would stop the launch itself"
        )

    def _refused(self, what: str) -> StatusResponse:
        return StatusResponse(
            False,
            f"{what}: models cannot be added or removed once time runs (Drake's plant "
            f"is fixed when built); spawn them with spawn_model nodes in the launch file",
        )

    def spawn_urdf_model(self, **request) -> StatusResponse:
        return self._refused("SpawnModel")

    def spawn_sdf_model(self, **request) -> StatusResponse:
        return self._refused("SpawnModel")

    def delete_model(self, model_name: str = "") -> StatusResponse:
        return self._refused(f"DeleteModel [{model_name}]")

    # -- between slices of simulated time ----------------------------------------------------
    def apply_pending(self) -> None:
        from ..world.model_states import reset_to_defaults, set_free_body_state

        for change in self.pending:
            if change[0] == "reset":
                reset_to_defaults(self.sim)
            else:
                try:
                    set_free_body_state(self.sim, *change[1:])
                except ValueError as exc:
                    self.node.log.error("/gazebo/set_model_state: %s", exc)
        self.pending.clear()
