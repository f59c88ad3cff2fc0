"""gazebo's role: the simulated world. Creates the Drake plant, loads the world SDF and hosts the
Gazebo plugins of the descriptions spawned into it.

Node types ``twil_control/drake_world`` (``~world``) and ``gazebo_ros/gzserver`` / ``gazebo``
(the world as gzserver's positional argument, its options accepted); name it ``gazebo``, as
roslaunch users do. The world is found and read as Gazebo does (docs/robots.md). The node also
watches the spawned robots (world/fall_monitor.py) and fails when one has left the world; it is
required by default, so the run stops there instead of recording a robot that falls for ever.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from twil_control.errors import InputError

from ..core import gazebo_paths
from ..core.messages import msg_class, time_msg
from ..core.param_rules import param
from ..core.ros_node import RosNode
from ..world.sdf_models import MAX_COLLISION_GEOMETRIES
from .plugins import PluginHost

#: Longest plant step accepted (s): at the robots' top speeds (about 1 m/s) a step moves them
#: at most a centimetre, a tenth of the worlds' 0.1 m walls.
MAX_TIME_STEP = 0.01

#: Gazebo's <max_step_size> when a world sets none (s)
GAZEBO_STEP = 0.001

#: gzserver's (and gazebo's) options that take a value; the world is the positional argument.
_VALUED_OPTIONS = {
    "-e",
    "--physics",
    "-p",
    "--play",
    "-s",
    "--server-plugin",
    "-g",
    "--gui-plugin",
    "-o",
    "--profile",
    "--record_encoding",
    "--record_path",
    "--record_period",
    "--record_filter",
    "--seed",
    "--iters",
}


def world_argument(args: list[str]) -> str | None:
    """The world file among gzserver's command-line args: the last one that is neither an
    option nor an option's value (None when there is none)."""
    world, skip = None, False
    for arg in args:
        if skip:
            skip = False
        elif arg in _VALUED_OPTIONS:
            skip = True
        elif arg.startswith("-") and arg != "-" or ":=" in arg:
            continue
        else:
            world = arg
    return world


@dataclass
class DrakeWorldParams:
    world: str = ""  # SDF file of the world (floor and obstacles)
    # The plant: fields of Drake's MultibodyPlantConfig (sampled_output_ports is its
    # use_sampled_output_ports); unset, world.simulation.plant_config's (Drake's defaults but for
    # point contact and ports computed when read).
    time_step: float | None = param(
        None,
        gt=0,
        le=MAX_TIME_STEP,
        why=(  # s (gazebo's max_step_size)
            "a longer step lets a robot move more than a centimetre between two contact checks (thin "
            "walls can be passed through); gazebo's default is 0.001"
        ),
    )
    contact_model: str | None = None
    discrete_contact_approximation: str | None = None
    penetration_allowance: float | None = param(None, gt=0)
    stiction_tolerance: float | None = param(None, gt=0)
    sampled_output_ports: bool | None = None
    # /clock (rosgraph_msgs/Clock) per simulated second; Gazebo's parameter. Gazebo publishes at
    # every physics step when it is 0 (its default); here 0 means every step too, and the
    # default is 100 Hz, as fine as the nodes' timers need and a tenth of the messages
    pub_clock_frequency: float = 100.0
    # /gazebo/model_states and link_states (gazebo/gazebo_services.py); Gazebo sends them at every
    # physics step while something listens; each costs a pass over every body's pose and velocity
    pub_model_states_frequency: float = 10.0
    # gazebo_ros's switch for its ROS topics and services (empty_world.launch sets it); here they
    # are in-process and always served: false is warned about
    enable_ros_network: bool = True
    fall_distance: float = param(1.0, gt=0)  # m below the world and the spawn height: left the world
    fall_check_rate: float = param(10.0, gt=0)  # Hz of simulated time
    max_collision_geometries: int = param(
        MAX_COLLISION_GEOMETRIES, ge=1
    )  # more: near the robots only (static_world)


class DrakeWorld(PluginHost, RosNode):
    required_by_default = True

    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(DrakeWorldParams)
        if not self.params.world:
            self.params.world = world_argument(self.args) or ""
        if not self.params.world:
            raise InputError(
                f"node {self.fqn}: no world file: set ~world or pass the world file as its "
                f"positional arg (args: {' '.join(self.args) or 'none'})"
            )
        self.plugins: list = []
        if not self.params.enable_ros_network:
            self.log.warning(
                "~enable_ros_network false ignored: the /gazebo topics and services are served in this "
                "process, and nothing outside it can reach them"
            )

    def build_systems(self, sim) -> None:
        from .gazebo_services import GazeboInterface

        f = self.params.pub_model_states_frequency
        if not (f > 0 and math.isfinite(f)):
            raise InputError(f"node {self.fqn}: ~pub_model_states_frequency must be > 0 Hz (got {f})")
        self.interface = GazeboInterface(self, sim, f)
        self.plugin_hook("build_systems", sim)
        from ..world.fall_monitor import FallMonitor

        self.fall_monitor = FallMonitor(sim, self.params.fall_distance)
        if self.fall_monitor.watched:
            self.create_timer(1.0 / self.params.fall_check_rate, self._check_falls)

    def _check_falls(self, event) -> None:
        fell = self.fall_monitor.check(self.sim.simulator.get_context(), event.current_expected)
        if fell is not None:
            self.fail(fell)

    def between_slices(self) -> None:
        """Model state changes the /gazebo services asked for (the runner calls this between
        slices of simulated time, where the simulator's context may be changed)."""
        self.interface.apply_pending()
        self.sim.update_proximity_window()  # after a model moved or a reset: its new place

    def on_start(self) -> None:
        self.plugin_hook("on_start")
        f = self.params.pub_clock_frequency
        if not (f >= 0 and math.isfinite(f)):
            raise InputError(f"node {self.fqn}: ~pub_clock_frequency must be >= 0 Hz (got {f})")
        self._clock_pub = self.create_publisher("/clock", "rosgraph_msgs/Clock")
        self._clock_msg = msg_class("rosgraph_msgs/Clock")
        self._publish_clock(None)
        self.create_timer(1.0 / f if f > 0 else self.sim_time_step, self._publish_clock)

    def _publish_clock(self, _event) -> None:
        self._clock_pub.publish(self._clock_msg(clock=time_msg(self.now())))

    def shutdown(self) -> None:
        self.plugin_hook("shutdown")

    def make_simulation(self):
        from ..description.gazebo_world import normalise
        from ..description.urdf import DescriptionError
        from ..world.simulation import Simulation, plant_config

        p = self.params
        try:
            path = gazebo_paths.resolve_world(p.world)
            world = normalise(path)
        except (gazebo_paths.WorldNotFoundError, DescriptionError) as error:
            raise InputError(f"node {self.fqn}: {error}") from None
        time_step = p.time_step
        if time_step is not None and time_step != (world.time_step or GAZEBO_STEP):
            # the user's world asks for its step: another one trades fidelity for speed, said aloud
            self.log.warning(
                "~time_step %g s: the plant steps every %g s where %s asks for %g s%s",
                time_step,
                time_step,
                world.source,
                world.time_step or GAZEBO_STEP,
                "" if world.time_step else " (Gazebo's default: the world sets no <max_step_size>)",
            )
        if time_step is None and world.time_step is not None:
            time_step = world.time_step
            if time_step > MAX_TIME_STEP:
                self.log.warning(
                    "%s: <max_step_size> %g s is longer than %g s: a robot could move more than a "
                    "centimetre between two contact checks; %g s is used",
                    world.source,
                    time_step,
                    MAX_TIME_STEP,
                    MAX_TIME_STEP,
                )
                time_step = MAX_TIME_STEP
        given = {
            "time_step": time_step,
            "contact_model": p.contact_model,
            "discrete_contact_approximation": p.discrete_contact_approximation,
            "penetration_allowance": p.penetration_allowance,
            "stiction_tolerance": p.stiction_tolerance,
            "use_sampled_output_ports": p.sampled_output_ports,
        }
        sim = Simulation(plant_config(**{name: value for name, value in given.items() if value is not None}))
        sim.add_world(world, max_collision_geometries=p.max_collision_geometries)
        for model in world.models:
            if model.robot is not None:  # a robot in the world file, with its plugins
                sim.limit_efforts(model.name, self.drive_effort_limits(model.robot))
                self.load_plugins(sim, model.name, model.robot, None)
        self.sim_time_step = sim.config.time_step
        self.sim = sim
        return sim
