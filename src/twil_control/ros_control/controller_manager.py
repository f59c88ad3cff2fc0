"""controller_manager::ControllerManager (ROS 1): load, unload, switch and update controllers.

The manager belongs to a node and advertises ROS's services under ``<ns>/controller_manager/``.
The rules are controller_manager.cpp's (Noetic) but for three: a switch is queued and performed
at the start of the next update() (the service does not block, so several spawners can ask
before the first update), a controller in both lists is refused, and a controller that raises
is aborted while the others run on. The rules: docs/ros_control.md. Refusals return False, log
the reason at ERROR and keep it in ``last_error``.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from twil_control.core import names
from twil_control.core.node import Node

from . import registry, srv
from .controller_interface import ABORTED, RUNNING, Controller, ControllerNodeHandle
from .hardware_interface import ControllerInfo, InterfaceResources, RobotHW, resource_conflicts
from .realtime_tools import publish_outbox
from .srv import BEST_EFFORT, STRICT, ControllerState

__all__ = ["BEST_EFFORT", "STRICT", "ControllerManager", "SERVICES"]

#: service names, relative to the manager node's namespace
SERVICES = (
    "controller_manager/list_controllers",
    "controller_manager/list_controller_types",
    "controller_manager/load_controller",
    "controller_manager/unload_controller",
    "controller_manager/switch_controller",
    "controller_manager/reload_controller_libraries",
)


@dataclass(eq=False)
class _Spec:
    """controller_manager::ControllerSpec."""

    info: ControllerInfo
    c: Controller
    subscriptions: list = field(default_factory=list)

    def release(self) -> None:
        for sub in self.subscriptions:
            sub.unregister()
        self.subscriptions.clear()


@dataclass
class _Switch:
    start: list[_Spec]
    stop: list[_Spec]


class _SwitchRefused(Exception):
    """A switch_controller request that is refused; its message is what _refuse logs."""


def _refuse_start_and_stop(start_controllers: Sequence[str], stop_controllers: Sequence[str]) -> None:
    both = [n for n in dict.fromkeys(start_controllers) if n in stop_controllers]
    if both:
        raise _SwitchRefused(
            f"Could not switch controllers: {', '.join(repr(n) for n in both)} in both the start and the "
            f"stop list (to restart a controller, stop it and start it with two switch_controller calls)"
        )


class ControllerManager:
    """The controller manager of one RobotHW, owned by (and advertising on) `node`."""

    def __init__(self, hw: RobotHW, node: Node, *, advertise: bool = True) -> None:
        self.hw = hw
        self.node = node
        self.log: logging.Logger = node.log
        self.last_error: str = ""
        self._specs: list[_Spec] = []
        self._update_order: tuple[_Spec, ...] = ()
        #: messages the controllers' RealtimePublishers filled in update(), delivered by
        #: publish_outbox() after the real-time cycle
        self.outbox: deque = deque()
        self._pending: list[_Switch] = []
        self._starting: list[_Spec] = []
        if advertise:
            handlers = {
                "controller_manager/list_controllers": self._srv_list_controllers,
                "controller_manager/list_controller_types": self._srv_list_controller_types,
                "controller_manager/load_controller": self._srv_load_controller,
                "controller_manager/unload_controller": self._srv_unload_controller,
                "controller_manager/switch_controller": self._srv_switch_controller,
                "controller_manager/reload_controller_libraries": self._srv_reload_libraries,
            }
            for name, handler in handlers.items():
                node.master.advertise_service(node.resolve(name), node.fqn, handler)

    # -- helpers -----------------------------------------------------------------------
    @property
    def namespace(self) -> str:
        return self.node.namespace

    def service_name(self, service: str) -> str:
        """The resolved name of one service, e.g. service_name("load_controller")."""
        return self.node.resolve("controller_manager/" + service)

    @property
    def switch_pending(self) -> bool:
        return bool(self._pending)

    def _refuse(self, message: str) -> bool:
        self.last_error = message
        self.log.error("%s", message)
        return False

    def _find(self, name: str) -> _Spec | None:
        for spec in self._specs:
            if spec.info.name == name:
                return spec
        return None

    def get_controller(self, name: str) -> Controller | None:
        """The controller instance (ControllerManager::getControllerByName), or None."""
        spec = self._find(name)
        return spec.c if spec else None

    def controller_names(self) -> list[str]:
        return [spec.info.name for spec in self._specs]

    def _projected_state(self, spec: _Spec) -> str:
        """The state `spec` will have once the queued switches are performed."""
        state = spec.c.state
        for sw in self._pending:
            if spec in sw.stop and state == RUNNING:
                state = "stopped"
            if spec in sw.start and state != ABORTED:
                state = RUNNING
        return state

    # -- load / unload -----------------------------------------------------------------
    def load_controller(self, name: str) -> bool:
        """ControllerManager::loadController."""
        self.last_error = ""
        if self._find(name) is not None:
            return self._refuse(
                f"A controller named '{name}' was already loaded inside the controller manager"
            )
        subscriptions: list = []
        try:
            root_nh = ControllerNodeHandle(self.node, self.node.namespace, subscriptions, self.outbox)
            controller_nh = root_nh.child(name)
        except names.GraphNameError as error:
            return self._refuse(
                f"Exception thrown while constructing nodehandle for controller with name '{name}': {error}"
            )
        type_param = names.join(controller_nh.namespace, "type")
        if not controller_nh.has_param("type"):
            return self._refuse(
                f"Could not load controller '{name}' because the type was not specified: parameter "
                f"'{type_param}' is not set. Did you load the controller configuration on the parameter "
                f"server (namespace: '{controller_nh.namespace}')?"
            )
        type_name = controller_nh.get_param("type")
        if not isinstance(type_name, str):
            return self._refuse(
                f"Could not load controller '{name}': parameter '{type_param}' must be a "
                f"controller type string such as 'effort_controllers/JointEffortController' "
                f"(got {type_name!r})"
            )
        try:
            cls = registry.get(type_name)
        except registry.ControllerTypeError as error:
            return self._refuse(
                f"Could not load controller '{name}' because controller type '{type_name}' "
                f"(parameter '{type_param}') cannot be loaded: {error}. Use 'rosservice call "
                f"controller_manager/list_controller_types' to get the available types"
            )
        try:
            controller = cls()
        except Exception as error:
            return self._refuse(f"Could not load class '{type_name}': {type(error).__name__}: {error}")
        controller.name = name
        controller.log = logging.getLogger(f"{self.log.name}.{name.replace('/', '.')}")
        for iface in cls.hardware_interfaces:
            if iface not in self.hw.interface_types():
                return self._refuse(
                    f"Initializing controller '{name}' failed: this controller requires a hardware interface "
                    f"of type '{iface}'. Make sure this is registered in the hardware_interface::RobotHW class "
                    f"(it has: {', '.join(self.hw.interface_types())})"
                )
        try:
            ok = controller.init_request(self.hw, root_nh, controller_nh)
        except Exception as error:
            ok = False
            controller.init_error = f"exception thrown in init(): {type(error).__name__}: {error}"
        if not ok:
            for sub in subscriptions:
                sub.unregister()
            reason = f": {controller.init_error}" if controller.init_error else ""
            return self._refuse(f"Initializing controller '{name}' failed{reason}")
        info = ControllerInfo(name, type_name, controller.claimed_resources())
        self._specs.append(_Spec(info, controller, subscriptions))
        self._update_order = tuple(self._specs)
        self.log.debug("Successfully loaded controller '%s' of type '%s'", name, type_name)
        return True

    def unload_controller(self, name: str) -> bool:
        """ControllerManager::unloadController."""
        self.last_error = ""
        spec = self._find(name)
        if spec is None:
            return self._refuse(
                f"Could not unload controller with name '{name}' because no controller with this name exists"
            )
        if any(spec in sw.start or spec in sw.stop for sw in self._pending):
            self._perform_switches(self.node.now())
        if spec.c.is_running():
            return self._refuse(f"Could not unload controller with name '{name}' because it is still running")
        self._specs.remove(spec)
        self._update_order = tuple(self._specs)
        spec.release()
        return True

    # -- switch ------------------------------------------------------------------------
    def switch_controller(
        self,
        start_controllers: Sequence[str] = (),
        stop_controllers: Sequence[str] = (),
        strictness: int = 0,
        start_asap: bool = False,
        timeout: float = 0.0,
    ) -> bool:
        """ControllerManager::switchController; the switch happens in the next update().

        start_asap and timeout are accepted for compatibility; switches here are immediate.
        """
        self.last_error = ""
        try:
            strict = self._is_strict(strictness)
            _refuse_start_and_stop(start_controllers, stop_controllers)
            requests = {
                verb: self._requested(verb, wanted, strict)
                for verb, wanted in (("stop", stop_controllers), ("start", start_controllers))
            }
            to_start, to_stop, after = self._plan_switch(requests["start"], requests["stop"], strict)
            self._check_hardware_takes(after, to_start, to_stop)
        except _SwitchRefused as refusal:
            return self._refuse(str(refusal))
        if to_start or to_stop:
            self._pending.append(_Switch(to_start, to_stop))
        return True

    def _is_strict(self, strictness: int) -> bool:
        """STRICT or BEST_EFFORT; 0 is taken as BEST_EFFORT with ROS's warning."""
        if strictness == 0:
            self.log.warning(
                "Controller Manager: To switch controllers you need to specify a strictness level "
                "of controller_manager_msgs::SwitchController::STRICT (%d) or ::BEST_EFFORT (%d). "
                "Defaulting to ::BEST_EFFORT.",
                STRICT,
                BEST_EFFORT,
            )
            strictness = BEST_EFFORT
        if strictness not in (BEST_EFFORT, STRICT):
            raise _SwitchRefused(
                f"Could not switch controllers: strictness {strictness} is neither "
                f"BEST_EFFORT ({BEST_EFFORT}) nor STRICT ({STRICT})"
            )
        return strictness == STRICT

    def _requested(self, verb: str, wanted: Sequence[str], strict: bool) -> list[_Spec]:
        """The loaded controllers named in one list, once each; an unknown name is refused
        under STRICT and skipped under BEST_EFFORT."""
        specs: list[_Spec] = []
        for name in wanted:
            spec = self._find(name)
            if spec is None:
                if strict:
                    raise _SwitchRefused(
                        f"Could not {verb} controller with name '{name}' because no "
                        f"controller with this name exists"
                    )
                self.log.debug(
                    "Could not %s controller with name '%s' because no controller with this name exists",
                    verb,
                    name,
                )
            elif spec not in specs:
                specs.append(spec)
        return specs

    def _plan_switch(
        self, start: list[_Spec], stop: list[_Spec], strict: bool
    ) -> tuple[list[_Spec], list[_Spec], list[ControllerInfo]]:
        """(to start, to stop, the controllers running after the switch), in loading order."""
        to_start: list[_Spec] = []
        to_stop: list[_Spec] = []
        after: list[ControllerInfo] = []
        for spec in self._specs:
            state = self._projected_state(spec)
            running = state == RUNNING
            in_stop, in_start = self._feasible_request(spec, state, spec in stop, spec in start, strict)
            if in_stop:
                to_stop.append(spec)
            if in_start:
                to_start.append(spec)
            if (running and not in_stop) or in_start:
                after.append(spec.info)
        return to_start, to_stop, after

    def _feasible_request(
        self, spec: _Spec, state: str, in_stop: bool, in_start: bool, strict: bool
    ) -> tuple[bool, bool]:
        """(stop it, start it): stopping what does not run, starting what runs or has aborted
        are refused under STRICT and dropped under BEST_EFFORT."""
        name = spec.info.name
        running = state == RUNNING
        if in_stop and not running:
            if strict:
                raise _SwitchRefused(
                    f"Could not stop controller '{name}' since it is not running (it is {state})"
                )
            in_stop = False
        if in_start and running:
            if strict:
                raise _SwitchRefused(f"Controller '{name}' is already running")
            in_start = False
        if in_start and state == ABORTED:
            if strict:
                raise _SwitchRefused(
                    f"Could not start controller '{name}' because it is aborted; unload it and load it again"
                )
            self.log.warning("Not starting controller '%s': it is aborted", name)
            in_start = False
        return in_stop, in_start

    def _check_hardware_takes(
        self, after: list[ControllerInfo], to_start: list[_Spec], to_stop: list[_Spec]
    ) -> None:
        """Refuse a switch that leaves a joint claimed twice or that the RobotHW rejects."""
        if self.hw.check_for_conflict(after):
            conflicts = resource_conflicts(after)
            detail = (
                "; ".join(
                    f"'{joint}' by {' and '.join(repr(c) for c in owners)}"
                    for joint, owners in conflicts.items()
                )
                or "the RobotHW reported a conflict"
            )
            raise _SwitchRefused(
                f"Could not switch controllers, due to resource conflict: after the switch "
                f"these joints would be claimed twice: {detail}"
            )
        if not self.hw.prepare_switch([s.info for s in to_start], [s.info for s in to_stop]):
            raise _SwitchRefused(
                "Could not switch controllers. The hardware interface combination for the "
                "requested controllers is unfeasible."
            )

    # -- real-time loop ----------------------------------------------------------------
    def update(self, time: float, period: float, reset_controllers: bool = False) -> None:
        """update_realtime(), then the realtime publishers' messages (for callers without a
        separate write() step, e.g. tests and hardware-less loops)."""
        self.update_realtime(time, period, reset_controllers)
        self.publish_outbox()

    def publish_outbox(self) -> None:
        """Deliver what the controllers' RealtimePublishers queued (realtime_tools' publishing
        thread); the simulated hardware loop calls it after write()."""
        if self.outbox:
            publish_outbox(self.outbox)

    def update_realtime(self, time: float, period: float, reset_controllers: bool = False) -> None:
        """ControllerManager::update: the queued switches, then update() of each running
        controller in load order. Never raises because of a controller."""
        if reset_controllers:  # motors re-enabled: restart the running controllers
            for spec in list(self._specs):
                if spec.c.is_running() and self._guarded(spec, "stopping", spec.c.stop_request, time, time):
                    self._guarded(spec, "starting", spec.c.start_request, time, time)
        if self._pending:
            self._perform_switches(time)
        for spec in self._update_order:  # a tuple: loads and unloads inside update() are safe
            c = spec.c
            if c.state == RUNNING:
                try:  # inlined _guarded: this loop runs at 1 kHz
                    c.update(time, period)
                except Exception as error:
                    self._abort(spec, "update", error, time)

    def _perform_switches(self, time: float) -> None:
        """ControllerManager::manageSwitch for every queued request: do_switch, stops, starts."""
        pending, self._pending = self._pending, []
        for sw in pending:
            self.hw.do_switch([s.info for s in sw.start], [s.info for s in sw.stop])
            self._starting = list(sw.start)
            for spec in sw.stop:
                if spec.c.is_running():
                    self._guarded(spec, "stopping", spec.c.stop_request, time, time)
            for spec in sw.start:
                if spec.c.state != ABORTED:
                    self._guarded(spec, "starting", spec.c.start_request, time, time)
            self._starting = []

    def _guarded(self, spec: _Spec, what: str, fn: Callable, time: float, *args) -> bool:
        try:
            fn(*args)
            return True
        except Exception as error:
            self._abort(spec, what, error, time)
            return False

    def _abort(self, spec: _Spec, what: str, error: Exception, time: float) -> None:
        message = (
            f"Controller '{spec.info.name}' ({spec.info.type}) raised in {what}(): "
            f"{type(error).__name__}: {error}; the controller is aborted, the others keep running "
            f"(unload and load it again to reuse it)"
        )
        self.last_error = message
        self.log.error("%s", message, exc_info=error)
        spec.c.state = ABORTED
        try:
            spec.c.abort_request(time)
        except Exception as again:
            self.log.error(
                "Controller '%s' also raised in aborting(): %s: %s",
                spec.info.name,
                type(again).__name__,
                again,
            )
        self._release(spec)

    def _release(self, spec: _Spec) -> None:
        """Free the joints of an aborted controller that no running or starting controller holds."""
        held = {
            j
            for other in self._specs + self._starting
            if other is not spec and (other.c.is_running() or other in self._starting)
            for r in other.info.claimed_resources
            for j in r.resources
        }
        free = [
            InterfaceResources(r.hardware_interface, [j for j in r.resources if j not in held])
            for r in spec.info.claimed_resources
        ]
        self.hw.do_switch([], [ControllerInfo(spec.info.name, spec.info.type, free)])

    # -- listing -----------------------------------------------------------------------
    def list_controllers(self) -> list[ControllerState]:
        """ControllerState(name, state, type, claimed_resources) of each loaded controller, in load order."""
        return [
            ControllerState(
                s.info.name,
                s.c.state,
                s.info.type,
                [
                    InterfaceResources(r.hardware_interface, list(r.resources))
                    for r in s.info.claimed_resources
                ],
            )
            for s in self._specs
        ]

    def list_controller_types(self) -> list[tuple[str, str]]:
        """(type, base class) pairs; the base class is always controller_interface::ControllerBase."""
        return [(t, registry.BASE_CLASS) for t in registry.types()]

    def reload_controller_libraries(self, force_kill: bool = False) -> bool:
        """Rescan the controller entry points. Refused while controllers are loaded, unless
        force_kill, which stops (at once) and unloads them first."""
        self.last_error = ""
        if self._specs and not force_kill:
            return self._refuse(
                f"Controller manager: Cannot reload controller libraries because there are still "
                f"{len(self._specs)} controllers loaded"
            )
        if self._specs:
            self.log.info("Controller manager: Killing all running controllers")
            self.switch_controller([], self.controller_names(), BEST_EFFORT)
            self._perform_switches(self.node.now())
            for name in list(reversed(self.controller_names())):
                if not self.unload_controller(name):
                    return self._refuse(
                        f"Controller manager: Cannot reload controller libraries because failed "
                        f"to unload controller '{name}'"
                    )
        registry.reload()
        return True

    # -- services (rospy ServiceProxy-style calls: a request object or its fields) -----------
    def _srv_load_controller(self, *args, **kwargs) -> srv.LoadControllerResponse:
        ok = self.load_controller(srv.request(srv.LoadControllerRequest, args, kwargs).name)
        return srv.LoadControllerResponse(ok, "" if ok else self.last_error)

    def _srv_unload_controller(self, *args, **kwargs) -> srv.UnloadControllerResponse:
        ok = self.unload_controller(srv.request(srv.UnloadControllerRequest, args, kwargs).name)
        return srv.UnloadControllerResponse(ok, "" if ok else self.last_error)

    def _srv_switch_controller(self, *args, **kwargs) -> srv.SwitchControllerResponse:
        req = srv.request(srv.SwitchControllerRequest, args, kwargs)
        ok = self.switch_controller(
            list(req.start_controllers),
            list(req.stop_controllers),
            req.strictness,
            req.start_asap,
            req.timeout,
        )
        return srv.SwitchControllerResponse(ok, "" if ok else self.last_error)

    def _srv_list_controllers(self, *args, **kwargs) -> srv.ListControllersResponse:
        srv.request(srv.ListControllersRequest, args, kwargs)
        return srv.ListControllersResponse(self.list_controllers())

    def _srv_list_controller_types(self, *args, **kwargs) -> srv.ListControllerTypesResponse:
        srv.request(srv.ListControllerTypesRequest, args, kwargs)
        pairs = self.list_controller_types()
        return srv.ListControllerTypesResponse([t for t, _ in pairs], [b for _, b in pairs])

    def _srv_reload_libraries(self, *args, **kwargs) -> srv.ReloadControllerLibrariesResponse:
        req = srv.request(srv.ReloadControllerLibrariesRequest, args, kwargs)
        return srv.ReloadControllerLibrariesResponse(self.reload_controller_libraries(req.force_kill))
