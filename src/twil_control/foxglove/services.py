"""The launch's services over the Foxglove protocol, in ROS 1 encoding.

Each controller manager of the launch offers ``switch_controller`` and ``list_controllers``
under its own name (``/qbot/controller_manager/switch_controller``), with the requests and
responses of controller_manager_msgs (Noetic), so Foxglove's Service Call panel sends the
same request a ROS user would give rosservice. amcl's ``global_localization`` and
``request_nomotion_update`` are std_srvs/Empty services (no fields either way). Requests are decoded here; the call itself is
made by the bridge in the simulation's thread (ros_control/srv.py's dataclasses are the
replica's service types).
"""

from __future__ import annotations

from dataclasses import dataclass

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from twil_control.errors import TwilControlError

from ..ros_control import srv

PKG = "controller_manager_msgs"

#: controller_manager_msgs (Noetic): the two halves of each .srv, and the messages they use
DEFINITIONS = {
    "SwitchControllerRequest": (
        "string[] start_controllers\nstring[] stop_controllers\nint32 strictness\n"
        "int32 BEST_EFFORT=1\nint32 STRICT=2\nbool start_asap\nfloat64 timeout\n"
    ),
    "SwitchControllerResponse": "bool ok\n",
    "ListControllersRequest": "",
    "ListControllersResponse": f"{PKG}/ControllerState[] controller\n",
    "ControllerState": (
        f"string name\nstring state\nstring type\n{PKG}/HardwareInterfaceResources[] claimed_resources\n"
    ),
    "HardwareInterfaceResources": "string hardware_interface\nstring[] resources\n",
}


#: services called with no request fields and answering none (std_srvs/Empty), by their base name
EMPTY_SERVICES = ("global_localization", "request_nomotion_update")
EMPTY = None  # the decoded request of an Empty service: called with no arguments


class ServiceInputError(TwilControlError, ValueError):
    """A request that cannot be decoded; the message says why."""


def _store():
    store = get_typestore(Stores.EMPTY)
    types = {}
    for name, text in DEFINITIONS.items():
        types.update(get_types_from_msg(text, f"{PKG}/msg/{name}"))
    for half in ("EmptyRequest", "EmptyResponse"):
        types.update(get_types_from_msg("", f"std_srvs/msg/{half}"))
    store.register(types)
    return store


@dataclass(frozen=True)
class ServiceSpec:
    """One service as the protocol advertises it, with its request and response halves."""

    name: str  # the graph name, e.g. /qbot/controller_manager/switch_controller
    srv_type: str  # controller_manager_msgs/SwitchController
    request_type: str  # typestore name of the request half
    response_type: str


class ControllerManagerServices:
    """Decodes requests, calls the replica's services and encodes their responses."""

    def __init__(self, service_names: list[str]) -> None:
        self.store = _store()
        self.specs: list[ServiceSpec] = []
        for name in sorted(service_names):
            for kind in ("switch_controller", "list_controllers"):
                if name.endswith(f"controller_manager/{kind}"):
                    srv_type = "SwitchController" if kind == "switch_controller" else "ListControllers"
                    self.specs.append(
                        ServiceSpec(
                            name,
                            f"{PKG}/{srv_type}",
                            f"{PKG}/msg/{srv_type}Request",
                            f"{PKG}/msg/{srv_type}Response",
                        )
                    )
            if name.rsplit("/", 1)[-1] in EMPTY_SERVICES:
                self.specs.append(
                    ServiceSpec(
                        name, "std_srvs/Empty", "std_srvs/msg/EmptyRequest", "std_srvs/msg/EmptyResponse"
                    )
                )

    def schema_text(self, typ: str) -> str:
        return self.store.generate_msgdef(typ)[0]

    def decode(self, spec: ServiceSpec, payload: bytes):
        """The replica's request object of a ROS 1 encoded request."""
        try:
            req = self.store.deserialize_ros1(bytes(payload), spec.request_type)
        except Exception as error:  # rosbags raises several types on short or garbled input
            raise ServiceInputError(
                f"{spec.name}: the request is not a ROS 1 encoded "
                f"{spec.srv_type}Request ({type(error).__name__}: {error})"
            ) from None
        if spec.srv_type == "std_srvs/Empty":
            return EMPTY
        if spec.srv_type.endswith("SwitchController"):
            return srv.SwitchControllerRequest(
                list(req.start_controllers),
                list(req.stop_controllers),
                int(req.strictness),
                bool(req.start_asap),
                float(req.timeout),
            )
        return srv.ListControllersRequest()

    def encode(self, spec: ServiceSpec, response) -> bytes:
        """ROS 1 bytes of the replica's response."""
        cls = self.store.types
        if spec.srv_type == "std_srvs/Empty":
            return b""
        if spec.srv_type.endswith("SwitchController"):
            msg = cls[spec.response_type](ok=bool(response.ok))
        else:
            res_cls, state_cls = (
                cls[f"{PKG}/msg/HardwareInterfaceResources"],
                cls[f"{PKG}/msg/ControllerState"],
            )
            msg = cls[spec.response_type](
                controller=[
                    state_cls(
                        name=c.name,
                        state=c.state,
                        type=c.type,
                        claimed_resources=[
                            res_cls(hardware_interface=r.hardware_interface, resources=list(r.resources))
                            for r in c.claimed_resources
                        ],
                    )
                    for c in response.controller
                ]
            )
        return bytes(self.store.serialize_ros1(msg, spec.response_type))
