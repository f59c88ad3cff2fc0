"""controller_manager_msgs (ROS 1): service requests, responses and ControllerState.

The services take what a rospy ServiceProxy takes: a request object, or the request fields
positionally or by keyword (``master.call_service(srv, "arm_controller")``,
``master.call_service(srv, [], ["a"], STRICT)``, ``master.call_service(srv,
SwitchControllerRequest(start_controllers=["a"], strictness=STRICT))``), and return responses
with ROS's field names (``resp.ok``, ``resp.controller[i].state``). Load, unload and switch
responses also carry the reason of a refusal in ``message`` (ROS logs it only), so that a spawner can
say why it failed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .hardware_interface import InterfaceResources

#: controller_manager_msgs/HardwareInterfaceResources has the fields of the C++ struct
HardwareInterfaceResources = InterfaceResources

#: SwitchController.srv strictness constants
BEST_EFFORT = 1
STRICT = 2


@dataclass
class ControllerState:
    """controller_manager_msgs/ControllerState."""

    name: str
    state: str
    type: str
    claimed_resources: list[InterfaceResources] = field(default_factory=list)


#: the name the brief of this package uses for it
ControllerStateInfo = ControllerState


@dataclass
class LoadControllerRequest:
    name: str


@dataclass
class UnloadControllerRequest:
    name: str


@dataclass
class SwitchControllerRequest:
    start_controllers: list[str] = field(default_factory=list)
    stop_controllers: list[str] = field(default_factory=list)
    strictness: int = 0
    start_asap: bool = False
    timeout: float = 0.0


@dataclass
class ListControllersRequest:
    pass


@dataclass
class ListControllerTypesRequest:
    pass


@dataclass
class ReloadControllerLibrariesRequest:
    force_kill: bool = False


def request(cls: type, args: tuple, kwargs: dict):
    """A request of type `cls` from a ServiceProxy-style call: a request object or its fields."""
    if len(args) == 1 and not kwargs and isinstance(args[0], cls):
        return args[0]
    return cls(*args, **kwargs)


@dataclass
class LoadControllerResponse:
    ok: bool
    message: str = ""  # the replica's addition: why a refusal (ROS only logs it)


@dataclass
class UnloadControllerResponse:
    ok: bool
    message: str = ""  # the replica's addition: why a refusal (ROS only logs it)


@dataclass
class SwitchControllerResponse:
    ok: bool
    message: str = ""  # the replica's addition: why a refusal (ROS only logs it)


@dataclass
class ReloadControllerLibrariesResponse:
    ok: bool


@dataclass
class ListControllersResponse:
    controller: list[ControllerState]


@dataclass
class ListControllerTypesResponse:
    types: list[str]
    base_classes: list[str]
