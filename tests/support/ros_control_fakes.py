"""Test doubles for the ros_control replica: a RobotHW with a trivial integrator, recording
controllers, and a loop that drives cm.update like the simulator's 1 kHz LeafSystem."""

from __future__ import annotations

import numpy as np

from twil_control.core.node import Master, Node
from twil_control.ros_control import EFFORT_JOINT_INTERFACE, Controller, ControllerManager, RobotHW, registry

NS = "/twil/ros_control"
DT = 0.001
JOINTS = ("j1", "j2", "j3")


class FakeHW(RobotHW):
    """Unit-inertia joints: effort -> acceleration, velocity and position commands are exact.

    A joint without an active mode gets zero effort (gazebo_ros_control's behaviour between
    controllers). Records prepare_switch/do_switch calls in `events` (shared with controllers).
    """

    def __init__(self, joints=JOINTS, modes=("effort", "velocity", "position"), events=None) -> None:
        super().__init__(joints, {j: list(modes) for j in joints})
        self.events = events if events is not None else []
        self.applied = np.zeros(len(joints))
        self.prepare_ok = True

    def prepare_switch(self, start_list, stop_list) -> bool:
        self.events.append(("prepare_switch", [c.name for c in start_list], [c.name for c in stop_list]))
        return self.prepare_ok and super().prepare_switch(start_list, stop_list)

    def do_switch(self, start_list, stop_list) -> None:
        self.events.append(("do_switch", [c.name for c in start_list], [c.name for c in stop_list]))
        super().do_switch(start_list, stop_list)

    def write(self, time: float, period: float) -> None:
        for i, joint in enumerate(self.joint_names):
            mode = self.active_mode(joint)
            if mode == "position":
                cmd = self.commands["hardware_interface::PositionJointInterface"][i]
                self.velocity[i] = (cmd - self.position[i]) / period
                self.position[i] = cmd
                self.effort[i] = 0.0
                continue
            if mode == "velocity":
                self.velocity[i] = self.commands["hardware_interface::VelocityJointInterface"][i]
                self.effort[i] = 0.0
            else:
                tau = self.commands[EFFORT_JOINT_INTERFACE][i] if mode == "effort" else 0.0
                self.effort[i] = tau
                self.velocity[i] += tau * period
            self.position[i] += self.velocity[i] * period


def make_cm(joints=JOINTS, ns=NS, params=None, events=None):
    """(master, cm node, hw, cm) with `params` set under the manager's namespace."""
    master = Master()
    for key, value in (params or {}).items():
        master.params.set(f"{ns}/{key}", value)
    node = Node(master, "controller_manager", namespace=ns)
    hw = FakeHW(joints, events=events)
    return master, node, hw, ControllerManager(hw, node)


def run(master, hw, cm, t0: float, steps: int, dt: float = DT) -> float:
    """Drive `steps` control cycles starting at t0 (read, update, write); returns the next time."""
    for k in range(steps):
        t = t0 + k * dt
        master.clock.set(t)
        hw.read(t, dt)
        cm.update(t, dt)
        hw.write(t, dt)
    return t0 + steps * dt


# -- recording controllers ------------------------------------------------------------------
EVENTS: list = []


class Recorder(Controller):
    """Claims param `joints` on the effort interface and records its lifecycle calls in EVENTS."""

    hardware_interfaces = (EFFORT_JOINT_INTERFACE,)

    def init(self, hw, root_nh, controller_nh) -> bool:
        self.handles = [
            hw.get_handle(EFFORT_JOINT_INTERFACE, j) for j in controller_nh.get_param("joints", [])
        ]
        self.updates = 0
        EVENTS.append(("init", self.name))
        return True

    def starting(self, time):
        EVENTS.append(("starting", self.name, time))

    def update(self, time, period):
        self.updates += 1
        EVENTS.append(("update", self.name, time))

    def stopping(self, time):
        EVENTS.append(("stopping", self.name, time))

    def aborting(self, time):
        EVENTS.append(("aborting", self.name, time))


class Raiser(Recorder):
    """Raises in its third update()."""

    def update(self, time, period):
        super().update(time, period)
        if self.updates == 3:
            raise ZeroDivisionError("boom in update")


class StopRaiser(Recorder):
    """Raises in stopping()."""

    def stopping(self, time):
        super().stopping(time)
        raise RuntimeError("cannot stop")


class InitFalse(Controller):
    def init(self, hw, root_nh, controller_nh) -> bool:
        return self.fail("the gains are missing")

    def update(self, time, period):
        pass


class InitRaise(Controller):
    def init(self, hw, root_nh, controller_nh) -> bool:
        raise RuntimeError("init exploded")


for _name, _cls in (
    ("test_controllers/Recorder", Recorder),
    ("test_controllers/Raiser", Raiser),
    ("test_controllers/StopRaiser", StopRaiser),
    ("test_controllers/InitFalse", InitFalse),
    ("test_controllers/InitRaise", InitRaise),
):
    registry.register(_name, _cls)


class PluginController(Recorder):
    """Only reachable through a (fake) entry point in the registry tests."""


class NotAController:
    pass
