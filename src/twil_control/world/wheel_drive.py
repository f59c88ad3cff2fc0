"""Joint velocity drives (Gazebo's joint velocity motor, as drive plugins use it): every
`period` a callback reads the plant's state and returns target velocities for some joints of
one model instance; Drake's implicit joint PD (gains set on their actuators before Finalize)
holds them, limited by the actuators' effort limits, until the next update.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import EventStatus, LeafSystem

from twil_control.errors import InputError


class WheelVelocityDrive(LeafSystem):
    """``update(t, x) -> target velocities`` of ``joints`` (in that order), every ``period``
    from t = 0; ``x`` is the plant's state [q, v]. The targets are held in the discrete state and
    drive the instance's desired-state input (desired positions are unused: the gains' p is 0)."""

    def __init__(self, sim, instance, joints: list[str], period: float, update) -> None:
        super().__init__()
        plant = sim.plant
        self._instance = instance
        self._update_cb = update
        order = [plant.get_joint_actuator(i).joint().name() for i in plant.GetJointActuatorIndices(instance)]
        missing = [j for j in joints if j not in order]
        if missing:
            raise InputError(f"joints {', '.join(missing)} have no actuator (actuated: {', '.join(order)})")
        n = len(order)
        self._slots = np.array([n + order.index(j) for j in joints], dtype=int)  # v_d slots
        joint_objs = [plant.GetJointByName(j, instance) for j in joints]
        self.q_index = np.array([j.position_start() for j in joint_objs], dtype=int)
        self.v_index = plant.num_positions() + np.array([j.velocity_start() for j in joint_objs], dtype=int)
        self._desired = np.zeros(2 * n)
        self._state_in = self.DeclareVectorInputPort("plant_state", plant.num_multibody_states())
        self._xd = self.DeclareDiscreteState(2 * n)
        self._out = self.DeclareStateOutputPort("desired_state", self._xd)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._on_update)

    def connect(self, sim) -> None:
        sim.builder.Connect(sim.plant.get_state_output_port(), self._state_in)
        sim.builder.Connect(self._out, sim.plant.get_desired_state_input_port(self._instance))

    def _on_update(self, context, discrete_state) -> EventStatus:
        x = self._state_in.Eval(context)
        targets = self._update_cb(context.get_time(), x)
        self._desired[self._slots] = targets
        discrete_state.set_value(self._xd, self._desired)
        return EventStatus.Succeeded()
