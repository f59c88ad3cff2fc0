"""A periodic reporter of one body's pose and velocity, read from the plant's outputs."""
from __future__ import annotations

import numpy as np
from pydrake.systems.framework import EventStatus, LeafSystem


class BodyStateReporter(LeafSystem):
    """Calls report(t, position, quaternion_xyzw, v_body, w_body) every `period` seconds,
    with the velocities expressed in the body's own frame (as nav_msgs/Odometry's twist)."""

    def __init__(self, sim, body, period: float, report, clock) -> None:
        super().__init__()
        self._index = int(body.index())
        self._report = report
        self._clock = clock
        self._poses = self.DeclareAbstractInputPort("body_poses", sim.plant.get_body_poses_output_port().Allocate())
        self._vels = self.DeclareAbstractInputPort(
            "body_spatial_velocities", sim.plant.get_body_spatial_velocities_output_port().Allocate())
        self.DeclarePeriodicPublishEvent(period, 0.0, self._on_tick)

    def connect(self, sim) -> None:
        sim.builder.Connect(sim.plant.get_body_poses_output_port(), self._poses)
        sim.builder.Connect(sim.plant.get_body_spatial_velocities_output_port(), self._vels)

    def _on_tick(self, context) -> EventStatus:
        t = context.get_time()
        self._clock.set(t)
        X_WB = self._poses.Eval(context)[self._index]
        V_WB = self._vels.Eval(context)[self._index]
        R_BW = X_WB.rotation().inverse()
        q = X_WB.rotation().ToQuaternion()
        quat = np.array([q.x(), q.y(), q.z(), q.w()])
        self._report(t, X_WB.translation(), quat, R_BW @ V_WB.translational(), R_BW @ V_WB.rotational())
        return EventStatus.Succeeded()
