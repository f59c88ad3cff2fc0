"""libgazebo_ros_control.so: the hardware adapter and controller manager of a spawned model, in
the simulator node, joints and interfaces from the URDF's ``<transmission>``s, as
DefaultRobotHWSim takes them (an SDF model's from the URDF in ``robotParam``).

Velocity and position joints without PID gains are held by Drake's implicit joint PD, stable at
any gain, where Gazebo sets the joint directly; mechanicalReduction is read and not applied, as
in DefaultRobotHWSim (docs/robots.md, "Plugins").
"""

from __future__ import annotations

from ...core.typed_params import load_typed
from ...description.urdf import DescriptionError, parse_urdf
from ..robot_hw_sim_node import start_hardware
from . import PluginNode

#: Implicit-PD gains standing in for Gazebo's direct velocity / position setting (N m s/rad,
#: N m/rad): stiff enough that a wheel follows its command within a few milliseconds.
VELOCITY_GAIN = 1000.0
POSITION_GAIN = 10000.0
POSITION_DAMPING = 200.0


class RosControlPlugin:
    def __init__(self, host, sim, model: str, config, description) -> None:
        from ...ros_control.hardware_interface import command_mode
        from ...world.robot_hw_sim import JointConfig, PidGainsConfig, set_implicit_pd_gains

        self.node = PluginNode(host, config.namespace)
        self.model = model
        self.period = config.control_period or sim.config.time_step
        self.joint_configs: dict[str, JointConfig] = {}
        params = host.master.params
        for transmission in _transmissions(params, config, description, self.node.fqn):
            description.joint(transmission.joint, f"transmission {transmission.name!r}")
            modes = []
            for interface in transmission.interfaces:
                try:
                    modes.append(command_mode(interface))
                except KeyError as exc:
                    raise DescriptionError(
                        f"{description.source}: transmission {transmission.name!r}: {exc}"
                    ) from None
            if not modes:
                raise DescriptionError(
                    f"{description.source}: transmission {transmission.name!r} "
                    f"names no hardwareInterface for joint {transmission.joint!r}"
                )
            gains_ns = f"{config.namespace.rstrip('/')}/gazebo_ros_control/pid_gains/{transmission.joint}"
            pid = load_typed(params, gains_ns, PidGainsConfig) if params.has(gains_ns) else None
            implicit = None
            if pid is None and "position" in modes:
                implicit = PidGainsConfig(p=POSITION_GAIN, d=POSITION_DAMPING)
            elif pid is None and "velocity" in modes:
                implicit = PidGainsConfig(p=0.0, d=VELOCITY_GAIN)
            self.joint_configs[transmission.joint] = JointConfig(modes, pid, implicit)
        if not self.joint_configs:
            raise DescriptionError(
                f"{description.source}: libgazebo_ros_control.so needs "
                f"<transmission> elements naming the joints it drives"
            )
        set_implicit_pd_gains(sim.plant, self.joint_configs, self.label)  # before Finalize()
        self.hw = self.manager = self.system = None

    @property
    def label(self) -> str:
        return f"{self.node.fqn} ({self.model}: gazebo_ros_control in {self.node.namespace})"

    def build_systems(self, sim) -> None:
        self.hw, self.manager, self.system = start_hardware(
            sim,
            self.node,
            self.model,
            self.joint_configs,
            self.period,
            f"{self.node.fqn}/{self.model}/gazebo_ros_control",
        )


def _transmissions(params, config, description, who: str) -> list:
    """The description's <transmission>s; an SDF model's come from the URDF of robotParam."""
    if description.transmissions or description.canonical is None:
        return description.transmissions
    parts = [p for p in config.namespace.split("/") if p]
    for depth in range(len(parts), -1, -1):
        key = "/" + "/".join(parts[:depth] + [config.robot_param.strip("/")])
        if params.has(key):
            text = params.get(key)
            if not isinstance(text, str):
                raise DescriptionError(f"{who}: {key} is not a URDF string")
            return parse_urdf(text, f"parameter {key}").transmissions
    raise DescriptionError(
        f"{description.source}: model {description.name!r} is SDF, and libgazebo_ros_control.so reads "
        f"the joints it drives from the <transmission>s of the URDF in parameter "
        f"{config.robot_param!r} (robotParam), which is not set in {config.namespace} or above"
    )
