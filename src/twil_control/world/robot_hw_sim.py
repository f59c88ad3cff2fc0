"""The hardware adapter (gazebo_ros_control's DefaultRobotHWSim) and the real-time loop.

`DrakeRobotHW` turns the active commands into actuator efforts (effort clipped to its limit, a
PID, or Drake's implicit joint PD: docs/robots.md); a NaN or inf command never reaches the plant.
`ControllerManagerSystem` runs read(), update(), write() as one periodic discrete update. Drake
steps the plant before the discrete updates at each t_k, so read() sees the state just computed
and the efforts drive the next step: gazebo_ros_control's order, with no period of delay between
the state read and the effort applied.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from pydrake.multibody.tree import JointActuatorIndex, PdControllerGains
from pydrake.systems.framework import EventStatus, LeafSystem

from twil_control.errors import InputError

from ..control.pid import Pid
from ..ros_control.hardware_interface import RobotHW
from .hw_kernels import clamp_and_scatter_efforts, implicit_commands

log = logging.getLogger("twil_control.robot_hw_sim")

MODES = ("effort", "velocity", "position")


@dataclass
class PidGainsConfig:
    ros_package: ClassVar[str] = "gazebo_ros_control"
    p: float = 0.0
    i: float = 0.0
    d: float = 0.0
    i_clamp: float = 0.0


@dataclass
class JointConfig:
    """One joint's transmission: the command interfaces it offers, and how velocity and
    position commands become effort (`pid` gains, or Drake's implicit PD `implicit_pd`)."""

    interfaces: list[str] = field(default_factory=lambda: ["effort"])
    pid: PidGainsConfig | None = None
    implicit_pd: PidGainsConfig | None = None  # p and d used; the plant integrates them implicitly


def set_implicit_pd_gains(plant, joints: dict[str, JointConfig], owner: str) -> None:
    """Give the actuators of `implicit_pd` joints their PD gains (before Finalize()). An
    actuator is found by the joint it drives (a URDF transmission may name it otherwise)."""
    by_joint = {}
    for i in range(plant.num_actuators()):
        actuator = plant.get_joint_actuator(JointActuatorIndex(i))
        by_joint[actuator.joint().name()] = actuator
    for name, cfg in joints.items():
        if cfg.implicit_pd:
            if name not in by_joint:
                raise InputError(f"{owner}: joint {name} has implicit_pd gains but no actuator")
            by_joint[name].set_controller_gains(PdControllerGains(p=cfg.implicit_pd.p, d=cfg.implicit_pd.d))


class DrakeRobotHW(RobotHW):
    """RobotHW over the actuated joints of some model instances of a Drake plant."""

    def __init__(self, plant, instances, joints: dict[str, JointConfig], node_name: str) -> None:
        self.plant = plant
        self.node_name = node_name
        self.instances = list(instances)
        actuators = []
        for instance in self.instances:
            actuators += [plant.get_joint_actuator(i) for i in plant.GetJointActuatorIndices(instance)]
        by_joint = {a.joint().name(): a for a in actuators}
        unknown = sorted(set(joints) - set(by_joint))
        if unknown:
            raise InputError(
                f"{node_name}: joints {', '.join(unknown)} in the transmission config are "
                f"not actuated joints of the model (actuated: {', '.join(sorted(by_joint))})"
            )
        names = [a.joint().name() for a in actuators if a.joint().name() in joints]
        super().__init__(names, {n: joints[n].interfaces for n in names})
        self.config = {n: joints[n] for n in names}
        acts = [by_joint[n] for n in names]
        self._q_index = np.array([a.joint().position_start() for a in acts])
        self._v_state_index = plant.num_positions() + np.array([a.joint().velocity_start() for a in acts])
        # The plant's whole actuation vector is ordered by actuator index; joints this adapter
        # does not drive stay at zero there.
        n_act = plant.num_actuators()
        order = [int(i) for i in plant.GetJointActuatorIndices()] if n_act else []
        slot_of = {idx: k for k, idx in enumerate(order)}
        self._scatter_slots = np.array([slot_of[int(a.index())] for a in acts], dtype=int)
        self.actuation = np.zeros(plant.num_actuated_dofs())
        self.desired_state = np.zeros(2 * plant.num_actuated_dofs())
        limits = np.array([a.effort_limit() for a in acts])
        self.effort_limit = np.where(np.isfinite(limits) & (limits > 0), limits, np.inf)
        #: the plant's whole state [q, v] of the last read (see read_state)
        self.plant_state = np.zeros(plant.num_multibody_states())
        self.simulation = self  # a SimulatedPlant: plant, instances, plant_state
        self._mode = np.zeros(len(names), dtype=int)  # 0 idle, 1 effort, 2 velocity, 3 position
        self._implicit = np.array([self.config[n].implicit_pd is not None for n in names], dtype=bool)
        # actuation = _tau_padded[_scatter]: slot k of the plant's actuation takes the effort of
        # joint _scatter[k]; slots of actuators not driven here point at the always-zero last
        # element of _tau_padded, so one fancy-index fills the whole vector.
        inverse = np.full(len(self.actuation), len(names), dtype=int)
        inverse[self._scatter_slots] = np.arange(len(names))
        self._tau_padded = np.zeros(len(names) + 1)
        self._tau = self._tau_padded[: len(names)]
        self._scatter = inverse
        self._effort_only = not any(c.implicit_pd for c in self.config.values())
        self._all_effort = False  # every joint commanded in effort mode (set by do_switch)
        self._active_modes = np.zeros(3, dtype=np.int64)  # effort, velocity, position: in use?
        self._pid_active = False  # a PID joint in velocity or position mode (set by do_switch)
        self._effort_cmd = self.commands.get("hardware_interface::EffortJointInterface", np.zeros(len(names)))
        self._pids = {
            n: Pid(c.pid.p, c.pid.i, c.pid.d, c.pid.i_clamp) for n, c in self.config.items() if c.pid
        }
        self._bad_reported: set[str] = set()
        # compile the write kernel now (numba caches it on disk), not in the first control period
        clamp_and_scatter_efforts(
            np.zeros(1),
            np.ones(1),
            np.zeros(2),
            np.zeros(1, dtype=self._scatter.dtype),
            np.zeros(1),
            np.zeros(1),
        )
        for name, cfg in self.config.items():
            for mode in ("velocity", "position"):
                if mode in self.supported_modes(name) and not (cfg.pid or cfg.implicit_pd):
                    raise InputError(
                        f"{node_name}: joint {name} offers the {mode} interface but has no "
                        "'pid' or 'implicit_pd' gains to turn commands into effort"
                    )
            if cfg.pid and cfg.implicit_pd:
                raise InputError(f"{node_name}: joint {name} has both 'pid' and 'implicit_pd'; choose one")
        # an SDF model's nested models (its laser) are instances of their own, without actuators
        actuated = [i for i in self.instances if plant.num_actuated_dofs(i) > 0]
        self.actuated_instance = actuated[0] if actuated else self.instances[0]
        if self.uses_implicit_pd and (
            len(actuated) != 1 or plant.num_actuated_dofs(actuated[0]) != plant.num_actuated_dofs()
        ):
            raise InputError(
                f"{node_name}: implicit_pd joints need the adapter to drive one model "
                "instance holding every actuator of the plant; use 'pid' gains instead"
            )

    @property
    def uses_implicit_pd(self) -> bool:
        return any(c.implicit_pd for c in self.config.values())

    # -- RobotHW ------------------------------------------------------------------------
    def read_state(self, x: np.ndarray) -> None:
        #: the plant's whole state [q, v] of the last read (gazebo's world access: controllers
        #: that need the true base pose, e.g. CartLinearizingController with pose_source
        #: ground_truth, read it here; it is the simulator's array, do not modify it)
        self.plant_state = x
        self.position[:] = x[self._q_index]
        self.velocity[:] = x[self._v_state_index]

    def write(self, time: float, period: float) -> None:
        """Active commands -> efforts: each joint's effort, then one compiled clamp and scatter
        (this runs every control period)."""
        if self._all_effort:  # the common case (one controller commands every joint's effort)
            efforts = self._effort_cmd
        else:
            efforts = self._tau
            efforts.fill(0.0)
            if self._effort_only:  # every command mode effort or idle
                np.copyto(efforts, self._effort_cmd, where=self._mode == 1)
            else:
                self._write_mixed(efforts, period)
        if not clamp_and_scatter_efforts(
            efforts, self.effort_limit, self._tau_padded, self._scatter, self.actuation, self.effort
        ):
            self._finite("effort")  # zero effort was applied; log the joint once

    def _write_mixed(self, tau: np.ndarray, period: float) -> None:
        """Velocity and position modes: PID joints compute effort here; implicit-PD joints
        set the desired state and leave the effort to the plant. Without an active PID joint,
        one compiled call does it all (hw_kernels.implicit_commands)."""
        if not self._pid_active:
            if not implicit_commands(
                self._mode,
                self._implicit,
                self._active_modes,
                self.command_rows,
                self.position,
                self.velocity,
                tau,
                self.desired_state,
                self._scatter_slots,
            ):
                for code, name in ((1, "effort"), (2, "velocity"), (3, "position")):
                    if self._active_modes[code - 1]:
                        self._finite(name)  # log each refused joint once
            return
        mode = self._mode
        desired_q, desired_v = self.position.copy(), self.velocity.copy()  # implicit PD idle
        for code, name in ((1, "effort"), (2, "velocity"), (3, "position")):
            active = mode == code
            if not active.any():
                continue
            cmd, bad = self._finite(name)
            active = active & ~bad  # a refused command leaves the joint with zero effort
            if code == 1:
                tau[active] = cmd[active]
                continue
            for i in np.flatnonzero(active & self._implicit):
                if code == 3:
                    desired_q[i], desired_v[i] = cmd[i], 0.0
                else:
                    desired_v[i] = cmd[i]
            for i in np.flatnonzero(active & ~self._implicit):
                pid = self._pids[self.joint_names[i]]
                if code == 3:
                    tau[i] = pid.compute_command(cmd[i] - self.position[i], -self.velocity[i], period)
                else:
                    tau[i] = pid.compute_command_from_error(cmd[i] - self.velocity[i], period)
        n = len(self.actuation)
        driven = self._scatter_slots
        self.desired_state[driven] = desired_q
        self.desired_state[n + driven] = desired_v

    def do_switch(self, start_list, stop_list) -> None:
        super().do_switch(start_list, stop_list)
        codes = {None: 0, "effort": 1, "velocity": 2, "position": 3}
        self._mode[:] = [codes[self.active_mode(n)] for n in self.joint_names]
        # Implicit-PD joints need their desired state refreshed every period, even when idle.
        self._effort_only = bool(np.all(self._mode <= 1)) and not self.uses_implicit_pd
        self._all_effort = bool(np.all(self._mode == 1)) and self._effort_only
        self._active_modes[:] = [bool(np.any(self._mode == code)) for code in (1, 2, 3)]
        self._pid_active = bool(np.any((self._mode >= 2) & ~self._implicit))
        for pid in self._pids.values():
            pid.reset()

    def _finite(self, mode: str) -> tuple[np.ndarray, np.ndarray]:
        values = self.command(mode)
        finite = np.isfinite(values)
        if finite.all():
            return values, ~finite
        for i in np.flatnonzero(~finite):
            joint = self.joint_names[i]
            if self._mode[i] and joint not in self._bad_reported:
                self._bad_reported.add(joint)
                log.error(
                    "%s: non-finite %s command %r for joint %s refused; the joint gets zero "
                    "effort (reported once)",
                    self.node_name,
                    mode,
                    float(values[i]),
                    joint,
                )
        return values, ~finite


def control_update_period(control_period: float, time_step: float) -> float:
    """The period the controllers run at, as gazebo_ros_control runs them: at the first physics
    step at least `control_period` after their last run, so every ceil(control_period /
    time_step) steps, and at every step (with the step as their period) when the control period
    is shorter than the step."""
    steps = max(1, math.ceil(control_period / time_step - 1e-9))
    return steps * time_step


class ControllerManagerSystem(LeafSystem):
    """Runs read() -> controller_manager.update() -> write() every `period` (a whole number of
    plant steps: control_update_period).

    Discrete state: the efforts of the plant's n actuators and, with implicit PD joints, the
    desired state [q (n), v (n)]; the output ports expose them to the plant's whole-plant
    actuation and desired-state inputs (one hardware adapter per simulated world).
    """

    def __init__(self, sim, hw: DrakeRobotHW, manager, clock, period: float) -> None:
        super().__init__()
        self._hw, self._manager, self._clock, self._period = hw, manager, clock, period
        plant = sim.plant
        n = len(hw.actuation)
        self._state_in = self.DeclareVectorInputPort("plant_state", plant.num_multibody_states())
        # Outputs are C++ views of the discrete state (DeclareStateOutputPort): a Python output
        # callback here would cost more than the plant's step itself.
        self._effort_xd = self.DeclareDiscreteState(n)
        self._ports = [
            (self.DeclareStateOutputPort("actuation", self._effort_xd), plant.get_actuation_input_port())
        ]
        self._desired_xd = None
        if hw.uses_implicit_pd:
            self._desired_xd = self.DeclareDiscreteState(2 * n)
            self._ports.append(
                (
                    self.DeclareStateOutputPort("desired_state", self._desired_xd),
                    plant.get_desired_state_input_port(hw.actuated_instance),
                )
            )
        #: per-update wall seconds, recorded only when a benchmark sets it to a list
        self.cost_log: list[float] | None = None
        # The cycle reads the state the plant's last step made, and the plant's next step uses
        # the efforts it writes, as gazebo_ros_control's update between two physics steps. Drake
        # runs the updates due at one time on the same state, so a cycle at the plant's own step
        # times would read the state before that step and drive the step after it (a period of
        # delay more, which takes computed torque off its closed form). A plant that samples its
        # outputs steps as an unrestricted update, which Drake runs before the discrete ones: the
        # cycle at t then reads the state of the step at t. Otherwise the cycle runs half a
        # plant step after the plant's steps. Either way the cycle that reads the result of the
        # step at t_k = k * period is labelled t_k.
        self._offset = 0.0 if sim.plant.has_sampled_output_ports() else 0.5 * sim.config.time_step
        self.DeclarePeriodicDiscreteUpdateEvent(period, self._offset, self._update)

    @property
    def period(self) -> float:
        """Seconds between two cycles (the period the controllers are given)."""
        return self._period

    def connect(self, sim) -> None:
        sim.builder.Connect(sim.plant.get_state_output_port(), self._state_in)
        for out, inp in self._ports:
            sim.builder.Connect(out, inp)

    def _update(self, context, discrete_state) -> EventStatus:
        start = time.perf_counter() if self.cost_log is not None else 0.0
        # t_k on the control grid exactly: t_k + h/2 - h/2 misses k * h by an ulp in about 1
        # cycle of 4,000, which a controller comparing times (a publish rate) could feel
        t = round((context.get_time() - self._offset) / self._period) * self._period
        self._clock.advance_to(t)  # an event between t_k and the cycle (the laser's) may be later
        self._hw.read_state(self._state_in.Eval(context))
        self._manager.update_realtime(t, self._period)
        self._hw.write(t, self._period)
        discrete_state.set_value(self._effort_xd, self._hw.actuation)  # cheaper than SetFromVector
        if self._desired_xd is not None:
            discrete_state.set_value(self._desired_xd, self._hw.desired_state)
        if self.cost_log is not None:
            self.cost_log.append(time.perf_counter() - start)
        self._manager.publish_outbox()  # realtime_tools' publishing thread: after the cycle
        return EventStatus.Succeeded()
