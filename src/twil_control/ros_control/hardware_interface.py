"""hardware_interface (ROS 1 ros_control): joint handles, interface types and RobotHW.

State lives in numpy arrays the RobotHW owns (``position``, ``velocity``, ``effort`` and one
command array per command interface); handles hold an index into them, so what ``read()``
writes in place (``hw.position[:] = q``) every handle sees with no copy. Never rebind those
arrays. A command-interface handle claims its joint, as ResourceManager's ClaimPolicy does
(docs/ros_control.md).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Final, Literal, Protocol, overload

import numpy as np

from twil_control.errors import TwilControlError

JOINT_STATE_INTERFACE: Final = "hardware_interface::JointStateInterface"
EFFORT_JOINT_INTERFACE: Final = "hardware_interface::EffortJointInterface"
VELOCITY_JOINT_INTERFACE: Final = "hardware_interface::VelocityJointInterface"
POSITION_JOINT_INTERFACE: Final = "hardware_interface::PositionJointInterface"

#: command mode (as a URDF transmission names it, short form) -> interface type name
COMMAND_INTERFACES: dict[str, str] = {
    "effort": EFFORT_JOINT_INTERFACE,
    "velocity": VELOCITY_JOINT_INTERFACE,
    "position": POSITION_JOINT_INTERFACE,
}
_MODE_OF = {iface: mode for mode, iface in COMMAND_INTERFACES.items()}


class HardwareInterfaceError(TwilControlError, KeyError):
    """A joint or interface the RobotHW does not have (hardware_interface::HardwareInterfaceException)."""


def command_mode(name: str) -> str:
    """Normalise a command interface name to "effort" | "velocity" | "position".

    Accepts the short form, the ROS type name (``hardware_interface::EffortJointInterface``)
    and the URDF transmission forms (``hardware_interface/EffortJointInterface``,
    ``EffortJointInterface``).
    """
    if name in COMMAND_INTERFACES:
        return name
    tail = name.replace("::", "/").rsplit("/", 1)[-1]
    for mode, iface in COMMAND_INTERFACES.items():
        if iface.endswith("::" + tail):
            return mode
    raise HardwareInterfaceError(
        f"unknown command interface '{name}'; use one of effort, velocity, position "
        f"(or {', '.join(COMMAND_INTERFACES.values())})"
    )


@dataclass
class InterfaceResources:
    """hardware_interface::InterfaceResources: the joints a controller claims on one interface."""

    hardware_interface: str
    resources: list[str] = field(default_factory=list)


@dataclass
class ControllerInfo:
    """hardware_interface::ControllerInfo: what prepare_switch/do_switch are told about a controller."""

    name: str
    type: str
    claimed_resources: list[InterfaceResources] = field(default_factory=list)


class JointStateHandle:
    """hardware_interface::JointStateHandle: read-only view of one joint's measured state."""

    __slots__ = ("name", "_state", "_i")

    def __init__(self, name: str, state: RobotHW) -> None:
        self.name = name
        self._state = state
        self._i = state.joint_index(name)

    @property
    def position(self) -> float:
        return float(self._state.position[self._i])

    @property
    def velocity(self) -> float:
        return float(self._state.velocity[self._i])

    @property
    def effort(self) -> float:
        return float(self._state.effort[self._i])

    # roscpp spelling
    def get_name(self) -> str:
        return self.name

    def get_position(self) -> float:
        return self.position

    def get_velocity(self) -> float:
        return self.velocity

    def get_effort(self) -> float:
        return self.effort

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r})"


class JointHandle(JointStateHandle):
    """hardware_interface::JointHandle: a JointStateHandle plus one command slot."""

    __slots__ = ("_cmd", "interface")

    def __init__(self, name: str, state: RobotHW, command: np.ndarray, interface: str) -> None:
        super().__init__(name, state)
        self._cmd = command
        self.interface = interface

    @property
    def command(self) -> float:
        return float(self._cmd[self._i])

    @command.setter
    def command(self, value: float) -> None:
        self._cmd[self._i] = value

    def set_command(self, value: float) -> None:
        self._cmd[self._i] = value

    def get_command(self) -> float:
        return float(self._cmd[self._i])


def resource_conflicts(info: Iterable[ControllerInfo]) -> dict[str, list[str]]:
    """{joint: [controller names]} for every joint claimed by more than one controller.

    The rule of RobotHW::checkForConflict: a resource listed by two controllers, on whatever
    interfaces, is a conflict. (ROS counts a MultiInterfaceController that claims one joint on
    two interfaces against itself; here one controller never conflicts with itself.)
    """
    claims: dict[str, list[str]] = {}
    for controller in info:
        for iface in controller.claimed_resources:
            for joint in iface.resources:
                owners = claims.setdefault(joint, [])
                if controller.name not in owners:
                    owners.append(controller.name)
    return {joint: owners for joint, owners in claims.items() if len(owners) > 1}


class SimulatedPlant(Protocol):
    """What a simulated RobotHW adds for the controllers that need the simulator's truth
    (gazebo_ros_control's world access): the Drake plant (typed Any: ros_control sees no Drake),
    the robot's model instances in it, and the plant's whole state [q, v] of the last read."""

    plant: Any
    instances: list
    plant_state: np.ndarray


class RobotHW:
    """hardware_interface::RobotHW for a set of joints.

    ``command_interfaces`` maps each joint to the command interfaces it supports (what its URDF
    transmission declares: "effort", "velocity", "position", or the ROS type names). Every
    joint has a JointStateInterface handle. Subclasses (the simulator's RobotHWSim) override
    ``read``/``write`` and may override ``prepare_switch``/``do_switch``.
    """

    def __init__(
        self, joint_names: Sequence[str], command_interfaces: Mapping[str, Iterable[str]] | None = None
    ) -> None:
        self.joint_names: tuple[str, ...] = tuple(joint_names)
        if len(set(self.joint_names)) != len(self.joint_names):
            raise HardwareInterfaceError(f"duplicate joint names in {list(self.joint_names)}")
        self._index = {name: i for i, name in enumerate(self.joint_names)}
        n = len(self.joint_names)
        self.position = np.zeros(n)
        self.velocity = np.zeros(n)
        self.effort = np.zeros(n)
        self._supported: dict[str, list[str]] = {name: [] for name in self.joint_names}
        for joint, modes in (command_interfaces or {}).items():
            if joint not in self._index:
                raise HardwareInterfaceError(
                    f"command interfaces given for unknown joint '{joint}' "
                    f"(joints: {', '.join(self.joint_names)})"
                )
            for mode in modes:
                mode = command_mode(mode)
                if mode not in self._supported[joint]:
                    self._supported[joint].append(mode)
        #: the effort, velocity and position commands as the rows of one array (a compiled
        #: write() reads them in one call); `commands` holds the rows of the supported interfaces
        self.command_rows = np.zeros((len(COMMAND_INTERFACES), n))
        #: interface type name -> command array (one slot per joint, in joint order)
        self.commands: dict[str, np.ndarray] = {
            iface: self.command_rows[row]
            for row, (mode, iface) in enumerate(COMMAND_INTERFACES.items())
            if any(mode in modes for modes in self._supported.values())
        }
        self._active: dict[str, str | None] = {name: None for name in self.joint_names}
        self._claims: dict[str, set[str]] = {}
        #: each joint's effort limit (N m or N; inf: none known)
        self.effort_limit: np.ndarray = np.full(n, np.inf)
        #: the simulator behind this hardware, when it is simulated (RobotHWSim); None otherwise
        self.simulation: SimulatedPlant | None = None

    # -- joints and interfaces ---------------------------------------------------------
    def joint_index(self, joint: str) -> int:
        try:
            return self._index[joint]
        except KeyError:
            raise HardwareInterfaceError(
                f"no joint named '{joint}' in the RobotHW (joints: {', '.join(self.joint_names)})"
            ) from None

    def interface_types(self) -> list[str]:
        """Registered interface type names (RobotHW::getNames): state first, then commands."""
        return [JOINT_STATE_INTERFACE] + [i for i in COMMAND_INTERFACES.values() if i in self.commands]

    def joints_of(self, interface_type: str) -> list[str]:
        """Joint names of one interface (HardwareResourceManager::getNames), in hw order."""
        if interface_type == JOINT_STATE_INTERFACE:
            return list(self.joint_names)
        mode = _MODE_OF.get(interface_type)
        return [j for j in self.joint_names if mode in self._supported[j]]

    def supported_modes(self, joint: str) -> list[str]:
        return list(self._supported[self.joint_names[self.joint_index(joint)]])

    def command(self, interface_type: str) -> np.ndarray:
        """The command array of one command interface (short or ROS name)."""
        iface = COMMAND_INTERFACES[command_mode(interface_type)]
        if iface not in self.commands:
            raise HardwareInterfaceError(
                f"no joint of this RobotHW has the {iface} (interfaces: {', '.join(self.interface_types())})"
            )
        return self.commands[iface]

    @overload
    def get_handle(
        self, interface_type: Literal["hardware_interface::JointStateInterface"], joint: str
    ) -> JointStateHandle: ...

    @overload
    def get_handle(self, interface_type: str, joint: str) -> JointHandle: ...

    def get_handle(self, interface_type: str, joint: str) -> JointStateHandle | JointHandle:
        """The handle of `joint` on `interface_type` (hw->get<Interface>()->getHandle(joint)).

        A command interface handle claims the joint for the controller being initialised
        (ClaimResources policy); a JointStateInterface handle claims nothing.
        """
        if interface_type not in self.interface_types():
            if interface_type in _MODE_OF or interface_type == JOINT_STATE_INTERFACE:
                raise HardwareInterfaceError(
                    f"cannot get joint '{joint}' from {interface_type}: no joint of this RobotHW has "
                    f"that interface (interfaces: {', '.join(self.interface_types())})"
                )
            raise HardwareInterfaceError(
                f"cannot get joint '{joint}': unknown interface type '{interface_type}' "
                f"(interfaces: {', '.join(self.interface_types())})"
            )
        if joint not in self._index:
            raise HardwareInterfaceError(
                f"could not find joint '{joint}' in '{interface_type}' "
                f"(joints: {', '.join(self.joints_of(interface_type))})"
            )
        if interface_type == JOINT_STATE_INTERFACE:
            return JointStateHandle(joint, self)
        if _MODE_OF[interface_type] not in self._supported[joint]:
            raise HardwareInterfaceError(
                f"could not find joint '{joint}' in '{interface_type}': its transmission declares "
                f"{', '.join(self._supported[joint]) or 'no command interface'}; joints with this "
                f"interface: {', '.join(self.joints_of(interface_type)) or 'none'}"
            )
        self._claims.setdefault(interface_type, set()).add(joint)
        return JointHandle(joint, self, self.commands[interface_type], interface_type)

    # -- claims (ResourceManager<ClaimResources>) --------------------------------------
    def clear_claims(self) -> None:
        self._claims = {}

    def get_claims(self) -> dict[str, list[str]]:
        """{interface: sorted joints} claimed since clear_claims() (a std::set, so sorted)."""
        return {iface: sorted(joints) for iface, joints in self._claims.items()}

    def check_for_conflict(self, info: Iterable[ControllerInfo]) -> bool:
        """RobotHW::checkForConflict: True when a joint would be claimed by two controllers."""
        return bool(resource_conflicts(info))

    # -- the real-time loop ------------------------------------------------------------
    def read(self, time: float, period: float) -> None:
        """Fill position/velocity/effort in place. No-op here; the simulator overrides it."""

    def write(self, time: float, period: float) -> None:
        """Send the active commands to the actuators. No-op here; the simulator overrides it."""

    # -- controller switching ----------------------------------------------------------
    def prepare_switch(
        self, start_list: Sequence[ControllerInfo], stop_list: Sequence[ControllerInfo]
    ) -> bool:
        """RobotHW::prepareSwitch (non-real-time): can this combination be switched to?

        The base accepts any start list whose claims exist on this hardware.
        """
        for controller in start_list:
            for iface in controller.claimed_resources:
                joints = (
                    set(self.joints_of(iface.hardware_interface))
                    if iface.hardware_interface in self.interface_types()
                    else set()
                )
                if any(j not in joints for j in iface.resources):
                    return False
        return True

    def do_switch(self, start_list: Sequence[ControllerInfo], stop_list: Sequence[ControllerInfo]) -> None:
        """RobotHW::doSwitch (real-time): set each claimed joint's active command mode.

        Joints of stopped controllers lose their mode (a simulator then applies zero effort);
        joints of started controllers take the mode of the interface they were claimed on.
        """
        for controller in stop_list:
            for iface in controller.claimed_resources:
                if iface.hardware_interface in _MODE_OF:
                    for joint in iface.resources:
                        self._active[joint] = None
        for controller in start_list:
            for iface in controller.claimed_resources:
                if iface.hardware_interface in _MODE_OF:
                    for joint in iface.resources:
                        self._active[joint] = _MODE_OF[iface.hardware_interface]

    def active_mode(self, joint: str) -> str | None:
        """ "effort" | "velocity" | "position" while a running controller commands `joint`, else None."""
        return self._active[self.joint_names[self.joint_index(joint)]]

    def finite_commands(self, interface_type: str) -> tuple[np.ndarray, list[str]]:
        """(a copy of the commands with non-finite entries set to 0.0, names of those joints).

        For write(): the simulator logs the bad joints once and applies zero for them.
        """
        values = self.command(interface_type).copy()
        bad = ~np.isfinite(values)
        if not bad.any():
            return values, []
        values[bad] = 0.0
        return values, [self.joint_names[i] for i in np.flatnonzero(bad)]
