"""The TWIL platform's mass properties from its description, for K5..K8 of (14)-(15).

`PlatformMassModel` parses the whole robot (``twil_wam``: TWIL with the WAM welded on its mount)
into its own continuous MultibodyPlant, the same description the simulated plant is built
from. For the arm at q it returns the planar rigid-body data the Newton-Euler derivation of
platform_model.derive_constants needs:

- mass m: every body of the robot (chassis, wheels, arm);
- d: x of the robot's centre of mass in base_link (ahead of the axle midpoint); the arm moves it;
- I: yaw inertia (zz) of the whole robot about the vertical through its centre of mass;
- Iw: the spin inertia of one driven wheel about its axle (the wheel link's inertia about the
  joint axis).

Assumptions (stated; the cart controller documents them too): the robot is treated as one rigid
body at the current arm pose (the arm's own motion and its reaction on the platform are not in
(8)); the lateral offset of the centre of mass (arm joint 1 away from 0) is neglected, as the
paper's model has no term for it; the floor is flat (base_link upright).
"""
from __future__ import annotations

import numpy as np
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

from . import models

__all__ = ["PlatformMassModel", "PlatformModelError", "MassProperties"]


class PlatformModelError(ValueError):
    """A description, link or joint list the platform model cannot be built from."""


class MassProperties(tuple):
    """(mass, com_offset_d, yaw_inertia, com_lateral) of the whole robot in base_link."""

    __slots__ = ()

    def __new__(cls, mass, d, yaw_inertia, lateral):
        return super().__new__(cls, (float(mass), float(d), float(yaw_inertia), float(lateral)))

    mass = property(lambda s: s[0])
    d = property(lambda s: s[1])
    yaw_inertia = property(lambda s: s[2])
    lateral = property(lambda s: s[3])


class PlatformMassModel:
    def __init__(self, description: str, arm_joints: list[str], wheel_joints: list[str],
                 base_link: str = "base_link") -> None:
        plant = MultibodyPlant(time_step=0.0)
        try:
            instances = models.add_model(plant, description, parser=Parser(plant))
        except models.ModelError as error:
            raise PlatformModelError(str(error)) from error
        plant.Finalize()
        self.plant = plant
        if not plant.HasBodyNamed(base_link):
            raise PlatformModelError(f"{description}: no link '{base_link}'")
        self.base = plant.GetBodyByName(base_link)
        missing = [j for j in list(arm_joints) + list(wheel_joints) if not plant.HasJointNamed(j)]
        if missing:
            raise PlatformModelError(f"{description}: joints {', '.join(missing)} are not joints of the description")
        self._arm_q = np.array([plant.GetJointByName(j).position_start() for j in arm_joints])
        self.bodies = [b for i in instances for b in plant.GetBodyIndices(i)]
        self.context = plant.CreateDefaultContext()
        wheel_Iw = []
        for j in wheel_joints:
            joint = plant.GetJointByName(j)
            axis = np.asarray(joint.revolute_axis()) if hasattr(joint, "revolute_axis") else np.array([0, 1.0, 0])
            I = joint.child_body().default_rotational_inertia().CopyToFullMatrix3()
            wheel_Iw.append(float(axis @ I @ axis))
        self.wheel_inertia = float(np.mean(wheel_Iw)) if wheel_Iw else 0.0

    def mass_properties(self, q_arm) -> MassProperties:
        plant, ctx = self.plant, self.context
        q = plant.GetPositions(ctx)
        q[self._arm_q] = q_arm
        plant.SetPositions(ctx, q)
        frame = self.base.body_frame()
        M = plant.CalcSpatialInertia(ctx, frame, self.bodies)  # about base_link origin, in base_link
        p_com = np.asarray(M.get_com())
        I_com = M.Shift(p_com).CalcRotationalInertia().CopyToFullMatrix3()
        return MassProperties(M.get_mass(), p_com[0], I_com[2, 2], p_com[1])
