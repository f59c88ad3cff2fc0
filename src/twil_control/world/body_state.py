"""A periodic reporter of one body's pose and velocity, read from the plant."""
from __future__ import annotations

from pydrake.systems.framework import EventStatus, LeafSystem

from ..control.transforms import qrot, unit_floats


class BodyStateReporter(LeafSystem):
    """Calls report(t, position, quaternion_xyzw, v_body, w_body) every `period` seconds,
    with the velocities expressed in the body's own frame (as nav_msgs/Odometry's twist).

    A floating base body (a mobile robot's base_link) is read from the plant's state alone: its
    floating joint's seven positions are the body's quaternion and position in the world, and
    its six velocities are its angular and translational velocity in the world. The rotations
    are plain float arithmetic. Through pydrake's RigidTransform, RotationMatrix and
    SpatialVelocity (as the ports and the scene graph give them) the same report cost about
    270 us at 100 Hz, a twentieth of the navigation launch's main thread; about 110 us of it
    remain, mostly building and publishing the messages (measured). Other bodies use the
    plant's body-pose and body-velocity ports, which hand Python every body of the world.
    """

    def __init__(self, sim, body, period: float, report, clock) -> None:
        super().__init__()
        self._index = int(body.index())
        self._report = report
        self._clock = clock
        plant = sim.plant
        # a free body gets a quaternion floating joint unless the model asks for another kind
        self._floating = body.is_floating_base_body() and body.has_quaternion_dofs()
        if self._floating:
            self._q0 = body.floating_positions_start()                       # qw qx qy qz px py pz
            self._v0 = plant.num_positions() + body.floating_velocities_start_in_v()  # w_WB v_WB
            self._state = self.DeclareVectorInputPort("plant_state", plant.num_multibody_states())
        else:
            self._poses = self.DeclareAbstractInputPort(
                "body_poses", plant.get_body_poses_output_port().Allocate())
            self._vels = self.DeclareAbstractInputPort(
                "body_spatial_velocities", plant.get_body_spatial_velocities_output_port().Allocate())
        self.DeclarePeriodicPublishEvent(period, 0.0, self._on_tick)

    def connect(self, sim) -> None:
        if self._floating:
            sim.builder.Connect(sim.plant.get_state_output_port(), self._state)
        else:
            sim.builder.Connect(sim.plant.get_body_poses_output_port(), self._poses)
            sim.builder.Connect(sim.plant.get_body_spatial_velocities_output_port(), self._vels)

    def body_state(self, context) -> tuple[tuple, tuple, tuple, tuple]:
        """(position in the world, quaternion (x, y, z, w) with w >= 0, translational and
        angular velocity in the body's frame) at this context, as tuples of floats."""
        if self._floating:
            x = self._state.Eval(context)
            w, qx, qy, qz, px, py, pz = x[self._q0:self._q0 + 7].tolist()
            wx, wy, wz, vx, vy, vz = x[self._v0:self._v0 + 6].tolist()
            # w >= 0, the sign RotationMatrix's ToQuaternion gives: both paths report the same
            quat = unit_floats((qx, qy, qz, w) if w >= 0.0 else (-qx, -qy, -qz, -w))
            q_bw = (-quat[0], -quat[1], -quat[2], quat[3])
            return (px, py, pz), quat, qrot(q_bw, (vx, vy, vz)), qrot(q_bw, (wx, wy, wz))
        X_WB, V_WB = self._poses.Eval(context)[self._index], self._vels.Eval(context)[self._index]
        R_BW = X_WB.rotation().inverse()
        q = X_WB.rotation().ToQuaternion()
        return (tuple(X_WB.translation().tolist()), (q.x(), q.y(), q.z(), q.w()),
                tuple((R_BW @ V_WB.translational()).tolist()), tuple((R_BW @ V_WB.rotational()).tolist()))

    def _on_tick(self, context) -> EventStatus:
        t = context.get_time()
        self._clock.set(t)
        self._report(t, *self.body_state(context))
        return EventStatus.Succeeded()
