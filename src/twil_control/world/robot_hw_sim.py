"""The hardware adapter (gazebo_ros_control's DefaultRobotHWSim) and the real-time loop.

`DrakeRobotHW` reads joint positions and velocities from the plant's state and turns the active
commands into actuator efforts:
- effort mode: the command, clipped to the joint's effort limit from the description;
- velocity / position mode with a PID (control_toolbox::Pid, gains from config), as
  gazebo_ros_control does when pid_gains are given;
- velocity / position mode with Drake's implicit joint PD (the actuator's PdControllerGains
  and the plant's desired-state input), stable at any gain because the plant's implicit
  solver integrates it, chosen per joint by config.
Commands that are NaN or inf never reach the plant: the joint gets zero effort and an error
is logged once per joint.

`ControllerManagerSystem` is the loop gazebo_ros_control runs each control period: read(),
controller_manager.update(), write(), as one periodic discrete update of a LeafSystem. The
efforts it computes at t_k are held in its discrete state and applied by the plant over
[t_k+1, t_k+2): one control period of delay, the same as a real robot's bus.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
from pydrake.multibody.tree import PdControllerGains
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

from ..control.pid import Pid
from ..ros_control.hardware_interface import RobotHW

log = logging.getLogger("twil_control.robot_hw_sim")

MODES = ("effort", "velocity", "position")


@dataclass
class PidGainsConfig:
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
    implicit_pd: PidGainsConfig | None = None   # p and d used; the plant integrates them implicitly


def set_implicit_pd_gains(plant, joints: dict[str, JointConfig], owner: str) -> None:
    """Give the actuators of `implicit_pd` joints their PD gains (before Finalize())."""
    for name, cfg in joints.items():
        if cfg.implicit_pd:
            if not plant.HasJointActuatorNamed(name):
                raise ValueError(f"{owner}: joint {name} has implicit_pd gains but no actuator")
            plant.GetJointActuatorByName(name).set_controller_gains(
                PdControllerGains(p=cfg.implicit_pd.p, d=cfg.implicit_pd.d))


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
            raise ValueError(f"{node_name}: joints {', '.join(unknown)} in the transmission config are "
                             f"not actuated joints of the model (actuated: {', '.join(sorted(by_joint))})")
        names = [a.joint().name() for a in actuators if a.joint().name() in joints]
        super().__init__(names, {n: joints[n].interfaces for n in names})
        self.config = {n: joints[n] for n in names}
        acts = [by_joint[n] for n in names]
        self._q_index = np.array([a.joint().position_start() for a in acts])
        self._v_index = np.array([a.joint().velocity_start() for a in acts])
        # Where each joint's effort goes: (model instance slot, index within its actuation vector).
        self._slot = []
        for a in acts:
            inst = self.instances.index(a.model_instance())
            order = list(plant.GetJointActuatorIndices(a.model_instance()))
            self._slot.append((inst, order.index(a.index())))
        self.actuation = [np.zeros(plant.num_actuated_dofs(i)) for i in self.instances]
        self.desired_state = [np.zeros(2 * plant.num_actuated_dofs(i)) for i in self.instances]
        limits = np.array([a.effort_limit() for a in acts])
        self.effort_limit = np.where(np.isfinite(limits) & (limits > 0), limits, np.inf)
        self._mode = np.zeros(len(names), dtype=int)  # 0 idle, 1 effort, 2 velocity, 3 position
        self._implicit = np.array([self.config[n].implicit_pd is not None for n in names], dtype=bool)
        self._scatter = []  # per instance: (joint indices, slots in its actuation vector)
        for k in range(len(self.instances)):
            joints = [i for i, (inst, _) in enumerate(self._slot) if inst == k]
            self._scatter.append((np.array(joints, dtype=int),
                                  np.array([self._slot[i][1] for i in joints], dtype=int)))
        self._pids = {n: Pid(c.pid.p, c.pid.i, c.pid.d, c.pid.i_clamp) for n, c in self.config.items() if c.pid}
        self._bad_reported: set[str] = set()
        for name, cfg in self.config.items():
            for mode in ("velocity", "position"):
                if mode in self.supported_modes(name) and not (cfg.pid or cfg.implicit_pd):
                    raise ValueError(f"{node_name}: joint {name} offers the {mode} interface but has no "
                                     "'pid' or 'implicit_pd' gains to turn commands into effort")
            if cfg.pid and cfg.implicit_pd:
                raise ValueError(f"{node_name}: joint {name} has both 'pid' and 'implicit_pd'; choose one")

    @property
    def uses_implicit_pd(self) -> bool:
        return any(c.implicit_pd for c in self.config.values())

    # -- RobotHW ------------------------------------------------------------------------
    def read_state(self, x: np.ndarray) -> None:
        self.position[:] = x[self._q_index]
        self.velocity[:] = x[self.plant.num_positions() + self._v_index]

    def write(self, time: float, period: float) -> None:
        """Active commands -> efforts, vectorised over joints (this runs every millisecond)."""
        mode = self._mode
        tau = np.zeros(len(self.joint_names))
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
        np.clip(tau, -self.effort_limit, self.effort_limit, out=tau)
        for k, (joints, slots) in enumerate(self._scatter):
            self.actuation[k][slots] = tau[joints]
            n = len(self.actuation[k])
            self.desired_state[k][slots] = desired_q[joints]
            self.desired_state[k][n + slots] = desired_v[joints]
        self.effort[:] = tau

    def do_switch(self, start_list, stop_list) -> None:
        super().do_switch(start_list, stop_list)
        codes = {None: 0, "effort": 1, "velocity": 2, "position": 3}
        self._mode[:] = [codes[self.active_mode(n)] for n in self.joint_names]
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
                log.error("%s: non-finite %s command %r for joint %s refused; the joint gets zero "
                          "effort (reported once)", self.node_name, mode, float(values[i]), joint)
        return values, ~finite


class ControllerManagerSystem(LeafSystem):
    """Runs read() -> controller_manager.update() -> write() every control period.

    Discrete state, per model instance k with n_k actuators: [actuation (n_k), desired
    positions (n_k), desired velocities (n_k)]; the output ports are slices of it.
    """

    def __init__(self, sim, hw: DrakeRobotHW, manager, clock, period: float) -> None:
        super().__init__()
        self._hw, self._manager, self._clock, self._period = hw, manager, clock, period
        plant = sim.plant
        self._nq = plant.num_positions()
        self._state_in = self.DeclareVectorInputPort("plant_state", plant.num_multibody_states())
        sizes = [len(a) for a in hw.actuation]
        self._blocks = []
        lo = 0
        for n in sizes:
            self._blocks.append((lo, n))
            lo += 3 * n
        self._xd = self.DeclareDiscreteState(lo)
        self._value = np.zeros(lo)
        ticket = {self.discrete_state_ticket(self._xd)}
        self._ports = []  # (output port, plant input port), wired by connect()
        for k, instance in enumerate(hw.instances):
            lo, n = self._blocks[k]
            port = self.DeclareVectorOutputPort(f"actuation_{k}", n, self._slice(lo, n), ticket)
            self._ports.append((port, plant.get_actuation_input_port(instance)))
            if hw.uses_implicit_pd:
                port = self.DeclareVectorOutputPort(f"desired_state_{k}", 2 * n, self._slice(lo + n, 2 * n), ticket)
                self._ports.append((port, plant.get_desired_state_input_port(instance)))
        #: per-update wall seconds, recorded only when a benchmark sets it to a list
        self.cost_log: list[float] | None = None
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)

    def connect(self, sim) -> None:
        sim.builder.Connect(sim.plant.get_state_output_port(), self._state_in)
        for out, inp in self._ports:
            sim.builder.Connect(out, inp)

    def _slice(self, lo: int, n: int):
        def calc(context, output: BasicVector) -> None:
            output.SetFromVector(context.get_discrete_state(self._xd).get_value()[lo:lo + n])
        return calc

    def _update(self, context, discrete_state) -> EventStatus:
        start = time.perf_counter() if self.cost_log is not None else 0.0
        t = context.get_time()
        self._clock.set(t)
        self._hw.read_state(self._state_in.Eval(context))
        self._manager.update(t, self._period)
        self._hw.write(t, self._period)
        for k, (lo, n) in enumerate(self._blocks):
            self._value[lo:lo + n] = self._hw.actuation[k]
            self._value[lo + n:lo + 3 * n] = self._hw.desired_state[k]
        discrete_state.get_mutable_vector(self._xd).SetFromVector(self._value)
        if self.cost_log is not None:
            self.cost_log.append(time.perf_counter() - start)
        return EventStatus.Succeeded()
