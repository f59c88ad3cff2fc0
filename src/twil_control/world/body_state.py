"""A periodic reporter of one body's pose and velocity, read from the plant."""

from __future__ import annotations

from pydrake.systems.framework import EventStatus, LeafSystem

from ..control.transforms import qmul, qrot, unit_floats


def floating_pose_twist(x, q0: int, v0: int) -> tuple[tuple, tuple, tuple, tuple]:
    """A quaternion-floating body's (position, quaternion (x, y, z, w) with w >= 0, velocity,
    angular velocity), all in the world frame, from the plant's state ``x``: its floating joint's
    seven positions start at ``q0``, its six velocities (angular first) at ``v0`` of ``x``."""
    w, qx, qy, qz, px, py, pz = x[q0 : q0 + 7].tolist()
    wx, wy, wz, vx, vy, vz = x[v0 : v0 + 6].tolist()
    # w >= 0, the sign RotationMatrix's ToQuaternion gives: both paths report the same
    quat = unit_floats((qx, qy, qz, w) if w >= 0.0 else (-qx, -qy, -qz, -w))
    return (px, py, pz), quat, (vx, vy, vz), (wx, wy, wz)


def floating_indices(plant, body) -> tuple[int, int]:
    """(q0, v0) of a quaternion-floating body in the plant's state [q, v]."""
    return body.floating_positions_start(), plant.num_positions() + body.floating_velocities_start_in_v()


class BodyStateReporter(LeafSystem):
    """Calls report(t, position, quaternion_xyzw, v_body, w_body) every `period` seconds,
    with the velocities expressed in the body's own frame (as nav_msgs/Odometry's twist).

    A floating base body (a mobile robot's base_link) is read from the plant's state alone: its
    floating joint's seven positions are the body's quaternion and position in the world, and
    its six velocities are its angular and translational velocity in the world. The rotations
    are plain float arithmetic: pydrake's RigidTransform, RotationMatrix and SpatialVelocity
    objects (as the ports and the scene graph give them) cost more than the rest of the report
    together. A body welded to a floating body (a sensor link of a mobile robot) is that body's
    state composed with the fixed offset between them. Other bodies use the plant's body-pose and
    body-velocity ports, which hand Python every body of the world.
    """

    def __init__(self, sim, body, period: float, report, clock) -> None:
        super().__init__()
        self._index = int(body.index())
        self._report = report
        self._clock = clock
        plant = sim.plant
        # a free body gets a quaternion floating joint unless the model asks for another kind
        self._floating = body.is_floating_base_body() and body.has_quaternion_dofs()
        # a body welded to a free body (a sensor link): that body's state and the fixed offset
        self._offset = None
        if not self._floating:
            carrier = next(
                (
                    b
                    for b in plant.GetBodiesWeldedTo(body)
                    if b.is_floating_base_body() and b.has_quaternion_dofs()
                ),
                None,
            )
            if carrier is not None:
                X = plant.CalcRelativeTransform(
                    plant.CreateDefaultContext(), carrier.body_frame(), body.body_frame()
                )
                q = X.rotation().ToQuaternion()
                self._offset = (tuple(X.translation().tolist()), (q.x(), q.y(), q.z(), q.w()))
                self._floating, body = True, carrier
        if self._floating:
            self._q0, self._v0 = floating_indices(plant, body)  # qw qx qy qz px py pz; w_WB v_WB
            self._state = self.DeclareVectorInputPort("plant_state", plant.num_multibody_states())
        else:
            self._poses = self.DeclareAbstractInputPort(
                "body_poses", plant.get_body_poses_output_port().Allocate()
            )
            self._vels = self.DeclareAbstractInputPort(
                "body_spatial_velocities", plant.get_body_spatial_velocities_output_port().Allocate()
            )
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
            position, quat, v_w, w_w = floating_pose_twist(self._state.Eval(context), self._q0, self._v0)
            if self._offset is not None:  # the welded body: p + R r, q q_off, v + w x R r
                r = qrot(quat, self._offset[0])
                position = (position[0] + r[0], position[1] + r[1], position[2] + r[2])
                quat = unit_floats(qmul(quat, self._offset[1]))
                v_w = (
                    v_w[0] + w_w[1] * r[2] - w_w[2] * r[1],
                    v_w[1] + w_w[2] * r[0] - w_w[0] * r[2],
                    v_w[2] + w_w[0] * r[1] - w_w[1] * r[0],
                )
            q_bw = (-quat[0], -quat[1], -quat[2], quat[3])
            return position, quat, qrot(q_bw, v_w), qrot(q_bw, w_w)
        X_WB, V_WB = self._poses.Eval(context)[self._index], self._vels.Eval(context)[self._index]
        R_BW = X_WB.rotation().inverse()
        q = X_WB.rotation().ToQuaternion()
        return (
            tuple(X_WB.translation().tolist()),
            (q.x(), q.y(), q.z(), q.w()),
            tuple((R_BW @ V_WB.translational()).tolist()),
            tuple((R_BW @ V_WB.rotational()).tolist()),
        )

    def _on_tick(self, context) -> EventStatus:
        t = context.get_time()
        self._clock.set(t)
        self._report(t, *self.body_state(context))
        return EventStatus.Succeeded()
