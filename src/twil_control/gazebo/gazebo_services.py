"""The simulator node's ROS interface, as gazebo_ros_api_plugin gives it in /gazebo.

/gazebo/model_states and link_states, set_model_state, and the services get_model_state,
set_model_state, reset_world, reset_simulation, (un)pause_physics, get/set_physics_properties,
spawn_*_model and delete_model, with gazebo_msgs' field names. Where they differ, and why (a
state set applies at the end of the current slice, time is never reset, pausing is refused
because every node runs on simulated time, the plant and its step are fixed once time runs):
docs/robots.md, "The ROS graph".
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
    "get_physics_properties",
    "set_physics_properties",
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


@dataclass
class OdePhysics:
    """gazebo_msgs/ODEPhysics, with Gazebo's defaults: ODE's solver settings, which Drake's plant
    does not have (reported as Gazebo's defaults, ignored when set)."""

    auto_disable_bodies: bool = False
    sor_pgs_precon_iters: int = 0
    sor_pgs_iters: int = 50
    sor_pgs_w: float = 1.3
    sor_pgs_rms_error_tol: float = 0.0
    contact_surface_layer: float = 0.001
    contact_max_correcting_vel: float = 100.0
    cfm: float = 0.0
    erp: float = 0.2
    max_contacts: int = 20


@dataclass
class GetPhysicsPropertiesResponse:
    time_step: float = 0.0
    pause: bool = False
    max_update_rate: float = 0.0  # steps per wall second Gazebo paces to; 0: as fast as possible
    gravity: object = None  # geometry_msgs/Vector3
    ode_config: OdePhysics = field(default_factory=OdePhysics)
    success: bool = False
    status_message: str = ""


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

    def _physics(self) -> tuple[float, float, tuple[float, float, float]]:
        """(time step, max update rate, gravity) of the running plant; the rate is the launch's
        real-time factor (--realtime) in steps per second, 0 when it runs as fast as it can."""
        step = self.sim.config.time_step
        simulator = self.sim.simulator
        rate = simulator.get_target_realtime_rate() / step if simulator is not None else 0.0
        gx, gy, gz = (float(g) for g in self.sim.plant.gravity_field().gravity_vector())
        return step, rate, (gx, gy, gz)

    def get_physics_properties(self) -> GetPhysicsPropertiesResponse:
        step, rate, g = self._physics()
        vector = msg_class("geometry_msgs/Vector3")(x=g[0], y=g[1], z=g[2])
        return GetPhysicsPropertiesResponse(
            step, False, rate, vector, OdePhysics(), True, "GetPhysicsProperties: got properties"
        )

    def set_physics_properties(
        self, time_step: float = 0.0, max_update_rate: float = 0.0, gravity=None, ode_config=None
    ) -> StatusResponse:
        """Succeeds when the request asks for the physics that runs (gravity None: unchanged;
        ode_config ignored); any change is refused, naming where it is set before the launch."""
        step, rate, g = self._physics()
        refused = []
        if abs(time_step - step) > 1e-12:
            refused.append(
                f"time_step {time_step:g} s (running: {step:g} s; set the world's <max_step_size> or "
                f"the /gazebo node's ~time_step before the launch starts)"
            )
        if abs(max_update_rate - rate) > 1e-9 * max(1.0, rate):
            refused.append(
                f"max_update_rate {max_update_rate:g} (running: {rate:g}; the launch's --realtime "
                f"paces it, 0: as fast as possible)"
            )
        if (
            gravity is not None
            and max(abs(a - b) for a, b in zip((gravity.x, gravity.y, gravity.z), g)) > 1e-12
        ):
            refused.append(
                f"gravity ({gravity.x:g}, {gravity.y:g}, {gravity.z:g}) (running: {g[0]:g}, {g[1]:g}, "
                f"{g[2]:g}; set it in the world's <gravity>)"
            )
        if refused:
            message = (
                "SetPhysicsProperties: the physics of Drake's plant is fixed once it is built; not "
                "applied: " + "; ".join(refused)
            )
            self.node.log.warning("/gazebo/set_physics_properties: %s", message)
            return StatusResponse(False, message)
        return StatusResponse(True, "physics engine updated")

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
