"""The arm's control model: M(q), C(q, qd) qd and tau_g(q) from Drake, built from the SAME
description as the simulated plant (no ROS here), so that computed torque cancels the plant.

`ArmControlModel` parses the arm into its own continuous plant with ``root_link`` welded to the
world, in the simulated plant's gravity. The arm's base is taken as fixed: the platform's
accelerations are left out, which is the cart controller's job (docs/computed_torque.md).
`inverse_dynamics(q, qd, a)` is law (53) in two Drake calls, cheaper than `terms()`'s three calls
and a product (kept for tests and analysis); the figures are on the performance page.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import MultibodyForces

from twil_control.errors import TwilControlError

from . import models

__all__ = ["ArmControlModel", "ArmModelError"]


class ArmModelError(TwilControlError, ValueError):
    """A description, root link or joint list the control model cannot be built from."""


class ArmControlModel:
    """Rigid-body dynamics of an arm on a fixed base, for computed torque control."""

    def __init__(
        self,
        description: str | Path,
        joints: list[str],
        root_link: str = "wam_base_link",
        gravity=(0.0, 0.0, -9.81),
        R_WB: np.ndarray | None = None,
    ) -> None:
        self.description = description
        self.joint_names = list(joints)
        plant = MultibodyPlant(time_step=0.0)
        try:
            instances = models.add_model(plant, description, parser=Parser(plant))
        except models.ModelError as error:
            raise ArmModelError(str(error)) from error
        if not plant.HasBodyNamed(root_link):
            bodies = sorted({plant.get_body(b).name() for i in instances for b in plant.GetBodyIndices(i)})
            raise ArmModelError(
                f"{description}: root_link '{root_link}' is not a link of the description "
                f"(links: {', '.join(bodies)})"
            )
        root = plant.GetBodyByName(root_link)
        if not _is_welded_to_world(plant, root):
            R = RotationMatrix() if R_WB is None else RotationMatrix(np.asarray(R_WB, dtype=float))
            plant.WeldFrames(plant.world_frame(), root.body_frame(), RigidTransform(R, np.zeros(3)))
        elif R_WB is not None:
            raise ArmModelError(
                f"{description}: root_link '{root_link}' is already welded by the "
                "description; a base rotation cannot be applied"
            )
        g = np.asarray(gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ArmModelError(f"gravity must be 3 finite numbers, got {gravity!r}")
        plant.mutable_gravity_field().set_gravity_vector(g)
        plant.Finalize()
        self.plant = plant
        self.gravity = g
        missing = [j for j in self.joint_names if not plant.HasJointNamed(j)]
        if missing:
            names = [
                plant.get_joint(j).name()
                for j in plant.GetJointIndices()
                if plant.get_joint(j).num_velocities()
            ]
            raise ArmModelError(
                f"{description}: joints {', '.join(missing)} are not joints of the description "
                f"(movable joints: {', '.join(names)})"
            )
        if len(set(self.joint_names)) != len(self.joint_names):
            raise ArmModelError(f"joints list names a joint twice: {self.joint_names}")
        js = [plant.GetJointByName(j) for j in self.joint_names]
        bad = [j.name() for j in js if j.num_positions() != 1 or j.num_velocities() != 1]
        if bad:
            raise ArmModelError(f"joints {', '.join(bad)} are not 1-DOF joints")
        self.n = len(js)
        if plant.num_positions() != self.n or plant.num_velocities() != self.n:
            raise ArmModelError(
                f"{description} welded at '{root_link}' has {plant.num_velocities()} degrees of freedom, "
                f"but {self.n} joints are controlled: every movable joint of the chain must be listed"
            )
        self._qi = np.array([j.position_start() for j in js])
        self._vi = np.array([j.velocity_start() for j in js])
        self._identity = bool(
            np.array_equal(self._qi, np.arange(self.n)) and np.array_equal(self._vi, np.arange(self.n))
        )
        self.context = plant.CreateDefaultContext()
        self._x = np.zeros(2 * self.n)
        self._ix = None if self._identity else np.ix_(self._vi, self._vi)
        self._forces = MultibodyForces(plant)
        self._vdot = np.zeros(self.n)

    # -- evaluation -------------------------------------------------------------------------
    def set_state(self, q: np.ndarray, qd: np.ndarray) -> None:
        x = self._x
        if self._identity:
            x[: self.n] = q
            x[self.n :] = qd
        else:
            x[self._qi] = q
            x[self.n + self._vi] = qd
        self.plant.SetPositionsAndVelocities(self.context, x)

    def terms(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, C qd, tau_g) at (q, qd), in the controller's joint order."""
        self.set_state(q, qd)
        plant, ctx = self.plant, self.context
        M = plant.CalcMassMatrix(ctx)
        c = plant.CalcBiasTerm(ctx)
        tau_g = plant.CalcGravityGeneralizedForces(ctx)
        if self._identity:
            return M, c, tau_g
        return M[self._ix], c[self._vi], tau_g[self._vi]

    def inverse_dynamics(self, q: np.ndarray, qd: np.ndarray, a: np.ndarray) -> np.ndarray:
        """M(q) a + C(q, qd) qd - tau_g(q) in the controller's joint order: the torque that gives
        the joints the acceleration a (with a = the bracket of (53), law (53) itself).

        Gravity is the plant's only force element, so CalcForceElementsContribution fills the
        reused MultibodyForces with tau_g, and CalcInverseDynamics subtracts it."""
        self.set_state(q, qd)
        plant, ctx = self.plant, self.context
        plant.CalcForceElementsContribution(ctx, self._forces)
        if self._identity:
            return plant.CalcInverseDynamics(ctx, a, self._forces)
        self._vdot[self._vi] = a
        return plant.CalcInverseDynamics(ctx, self._vdot, self._forces)[self._vi]

    def measure_cost(self, calls: int = 2000, seed: int = 0) -> float:
        """Median wall seconds of one inverse_dynamics() call at random states."""
        rng = np.random.default_rng(seed)
        q, qd, a = rng.uniform(-1, 1, (3, self.n))
        samples = []
        for _ in range(calls):
            t0 = time.perf_counter()
            self.inverse_dynamics(q, qd, a)
            samples.append(time.perf_counter() - t0)
        return float(np.median(samples))


def _is_welded_to_world(plant: MultibodyPlant, body) -> bool:
    for j in plant.GetJointIndices():
        joint = plant.get_joint(j)
        if (
            joint.child_body().index() == body.index()
            and joint.num_velocities() == 0
            and joint.parent_body().index() == plant.world_body().index()
        ):
            return True
    return False


def plant_gravity_and_base(hw, root_link: str):
    """(gravity vector, R_WB or None) from the simulated plant behind `hw`, when it is one, so
    the control model uses the plant's gravity and base orientation (Drake's default gravity
    otherwise; R_WB None means upright)."""
    plant = getattr(hw, "plant", None)
    if plant is None:
        return (0.0, 0.0, -9.81), None
    gravity = np.array(plant.gravity_field().gravity_vector())
    R_WB = None
    if plant.HasBodyNamed(root_link):
        ctx = plant.CreateDefaultContext()
        R = plant.GetBodyByName(root_link).EvalPoseInWorld(ctx).rotation().matrix()
        if not np.allclose(R, np.eye(3), atol=1e-12):
            R_WB = R
    return gravity, R_WB
