"""Every body's pose and velocity in the world, for /gazebo/model_states and /gazebo/link_states,
and the model state changes the /gazebo services ask for (applied between simulated slices)."""

from __future__ import annotations

from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform
from pydrake.multibody.math import SpatialVelocity
from pydrake.systems.framework import EventStatus, LeafSystem

from twil_control.errors import InputError


class BodyStates(LeafSystem):
    """Calls ``report(t, links, models)`` every ``period``: ``links`` is [(``model::link``,
    position, quaternion (x, y, z, w), linear velocity, angular velocity)] of every body of the
    spawned models, in the world frame; ``models`` the same for each model's root body."""

    def __init__(self, sim, period: float, report, clock) -> None:
        super().__init__()
        plant = sim.plant
        self._report, self._clock = report, clock
        self._bodies, self._roots = [], []
        for model, instances in sim.robots.items():
            for instance in instances:
                for index in plant.GetBodyIndices(instance):
                    body = plant.get_body(index)
                    self._bodies.append((f"{model}::{body.name()}", int(index)))
                self._roots.append((model, int(_root_of(plant, instance).index())))
        self._poses = self.DeclareAbstractInputPort(
            "body_poses", plant.get_body_poses_output_port().Allocate()
        )
        self._vels = self.DeclareAbstractInputPort(
            "body_spatial_velocities", plant.get_body_spatial_velocities_output_port().Allocate()
        )
        self.DeclarePeriodicPublishEvent(period, 0.0, self._on_tick)

    def connect(self, sim) -> None:
        sim.builder.Connect(sim.plant.get_body_poses_output_port(), self._poses)
        sim.builder.Connect(sim.plant.get_body_spatial_velocities_output_port(), self._vels)

    def _on_tick(self, context) -> EventStatus:
        poses, vels = self._poses.Eval(context), self._vels.Eval(context)

        def state(name, index):
            X, V = poses[index], vels[index]
            q = X.rotation().ToQuaternion()
            return (
                name,
                tuple(X.translation().tolist()),
                (q.x(), q.y(), q.z(), q.w()),
                tuple(V.translational().tolist()),
                tuple(V.rotational().tolist()),
            )

        t = context.get_time()
        self._clock.set(t)
        self._report(t, [state(*b) for b in self._bodies], [state(*r) for r in self._roots])
        return EventStatus.Succeeded()


def _root_of(plant, instance):
    """The body a model's pose is (Gazebo's model frame: the root of its link tree): its floating
    base body, else its first body. A URDF may declare its wheels before base_link (Jackal's)."""
    bodies = [plant.get_body(index) for index in plant.GetBodyIndices(instance)]
    return next((body for body in bodies if body.is_floating_base_body()), bodies[0])


def model_root(sim, model: str):
    """The root body of a spawned model (its floating base body, else its first)."""
    return _root_of(sim.plant, sim.robot_instances(model)[0])


def get_free_body_state(sim, model: str):
    """(position, quaternion xyzw, linear velocity, angular velocity) of a model's root body now."""
    plant = sim.plant
    context = plant.GetMyContextFromRoot(sim.simulator.get_context())
    body = model_root(sim, model)
    X = plant.EvalBodyPoseInWorld(context, body)
    V = plant.EvalBodySpatialVelocityInWorld(context, body)
    q = X.rotation().ToQuaternion()
    return (
        tuple(X.translation().tolist()),
        (q.x(), q.y(), q.z(), q.w()),
        tuple(V.translational().tolist()),
        tuple(V.rotational().tolist()),
    )


def set_free_body_state(sim, model: str, position, quaternion, linear, angular) -> None:
    """Move a model's free root body (between simulated slices, never inside an event)."""
    plant = sim.plant
    context = plant.GetMyMutableContextFromRoot(sim.simulator.get_mutable_context())
    body = model_root(sim, model)
    if not body.is_floating_base_body():
        raise InputError(f"model {model!r} is welded to the world: its pose cannot be set")
    x, y, z, w = quaternion
    X = RigidTransform(Quaternion(w, x, y, z), list(position))
    plant.SetFreeBodyPose(context, body, X)
    plant.SetFreeBodySpatialVelocity(context, body, SpatialVelocity(list(angular), list(linear)))


def reset_to_defaults(sim) -> None:
    """Every model back to its spawn pose and joint positions, at rest (reset_world)."""
    plant = sim.plant
    context = plant.GetMyMutableContextFromRoot(sim.simulator.get_mutable_context())
    plant.SetDefaultState(context, context.get_mutable_state())


__all__ = ["BodyStates", "get_free_body_state", "model_root", "reset_to_defaults", "set_free_body_state"]
