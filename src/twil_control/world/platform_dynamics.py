"""The whole TWIL + WAM robot's control model: its mass matrix and inverse dynamics, for K5..K8
of (14)-(15) and computed torque on the moving platform.

`PlatformMassModel` loads the robot's description (``twil_wam``: TWIL with the WAM welded on
its mount) twice, from the same files the simulated plant is built from: into a continuous
Drake MultibodyPlant, which checks the description (the joints named, a free base, no joint
damping or reflected rotor inertia that the control model would miss) and gives the wheel spin
inertia and the welds between the models; and into a Pinocchio model (its URDFs, the
welds read from Drake), which computes the mass matrix (CRBA) and the inverse dynamics (RNEA)
at 1 kHz. Drake's CalcMassMatrix and CalcInverseDynamics give the same (tested to 1e-9
relative) but cost about 26 us a pair from Python against about 5 us for Pinocchio
(bench/cart_bench.py, bench/results/).

Pinocchio's coordinates (the layout of `q`, `v` and `a`): the base is a free flyer with
q = [x, y, z, qx, qy, qz, qw] (base_link's origin and orientation in the world) and
v = [v, w] (its origin's velocity and its angular velocity, both in base_link's axes); a
continuous wheel joint has q = [cos phi, sin phi].

For K5..K8 the robot is treated as one rigid body at the current arm pose
(platform_model.planar_mass_properties reads it off the mass matrix's base block): the arm's
own motion and its reaction on the platform are not in (8); the lateral offset of the centre of
mass is neglected, as the paper's model has no term for it; the floor is flat.
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin
from pydrake.multibody.parsing import LoadModelDirectives, Parser
from pydrake.multibody.plant import MultibodyPlant

from twil_control.control.platform_model import planar_mass_properties

from . import models

__all__ = ["PlatformMassModel", "PlatformModelError", "MassProperties", "pinocchio_model"]


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


def _check_plant(plant: MultibodyPlant, description) -> None:
    """Refuse what Pinocchio's model of the URDFs would not hold: joint damping and reflected
    rotor inertia (the plant would feel them, the control model not), other joint types, and
    anything but one free body."""
    free = 0
    for i in plant.GetJointIndices():
        j = plant.get_joint(i)
        if j.type_name() not in ("revolute", "weld", "quaternion_floating"):
            raise PlatformModelError(f"{description}: joint '{j.name()}' is a {j.type_name()} joint: the control "
                                     "model takes revolute and weld joints below one free body")
        if np.any(np.asarray(j.default_damping_vector()) != 0.0):
            raise PlatformModelError(f"{description}: joint '{j.name()}' has damping {j.default_damping_vector()}: "
                                     "the control model has none")
        free += j.type_name() == "quaternion_floating"
    if free != 1:
        raise PlatformModelError(f"{description}: {free} free bodies: the control model takes exactly one")
    for a in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(a)
        if actuator.default_reflected_inertia() != 0.0:
            raise PlatformModelError(f"{description}: actuator '{actuator.name()}' has reflected rotor inertia: "
                                     "the control model has none")


def pinocchio_model(description, plant: MultibodyPlant) -> pin.Model:
    """The Pinocchio model of `description` (a URDF, or model directives adding URDFs and
    welding them), with the free base of the first URDF and the gravity of `plant`, the
    finalized Drake plant of the same description (the welds' poses are read from it)."""
    path = models.resolve(description)
    if path.suffix == ".urdf":
        files, welds = [path], []
    elif path.name.endswith((".dmd.yaml", ".dmd.yml")):
        directives = LoadModelDirectives(str(path)).directives
        files = [models.resolve(d.add_model.file.removeprefix("file://")) for d in directives if d.add_model]
        welds = [d.add_weld for d in directives if d.add_weld]
    else:
        raise PlatformModelError(f"{path}: the control model is built from URDF files or model directives "
                                 "adding URDFs")
    if any(f.suffix != ".urdf" for f in files) or len(welds) != len(files) - 1:
        raise PlatformModelError(f"{path}: the control model needs URDFs, each after the first welded to one "
                                 "before it")
    model = pin.buildModelFromUrdf(str(files[0]), pin.JointModelFreeFlyer())
    context = plant.CreateDefaultContext()
    for file, weld in zip(files[1:], welds):
        parent = weld.parent.split("::")[-1]
        child = pin.buildModelFromUrdf(str(file))
        if child.frames[1].name != weld.child.split("::")[-1] or not model.existFrame(parent):
            raise PlatformModelError(f"{path}: weld {weld.parent} -> {weld.child} must attach the root link of "
                                     f"{file.name} to a link before it")
        X = plant.CalcRelativeTransform(context, plant.GetFrameByName(parent),
                                        plant.GetFrameByName(weld.child.split("::")[-1]))
        model = pin.appendModel(model, child, model.getFrameId(parent), pin.SE3(X.rotation().matrix(),
                                                                                 X.translation()))
    model.gravity.linear[:] = plant.gravity_field().gravity_vector()
    return model


class PlatformMassModel:
    """The robot's control model (module docstring): `model` and `data` (Pinocchio), the state
    `q`, `v` and accelerations `a` in its coordinates, and where the wheels and arm joints are
    in them."""

    def __init__(self, description: str, arm_joints: list[str], wheel_joints: list[str],
                 base_link: str = "base_link") -> None:
        plant = MultibodyPlant(time_step=0.0)
        try:
            models.add_model(plant, description, parser=Parser(plant))
        except models.ModelError as error:
            raise PlatformModelError(str(error)) from error
        plant.Finalize()
        self.plant = plant
        if not plant.HasBodyNamed(base_link):
            raise PlatformModelError(f"{description}: no link '{base_link}'")
        missing = [j for j in list(arm_joints) + list(wheel_joints) if not plant.HasJointNamed(j)]
        if missing:
            raise PlatformModelError(f"{description}: joints {', '.join(missing)} are not joints of the description")
        if not plant.GetBodyByName(base_link).is_floating_base_body():
            raise PlatformModelError(f"{description}: '{base_link}' is not a free body")
        _check_plant(plant, description)
        wheel_Iw = []
        for j in wheel_joints:
            joint = plant.GetJointByName(j)
            axis = np.asarray(joint.revolute_axis())
            I = joint.child_body().default_rotational_inertia().CopyToFullMatrix3()
            wheel_Iw.append(float(axis @ I @ axis))
        self.wheel_inertia = float(np.mean(wheel_Iw)) if wheel_Iw else 0.0
        self.model = pinocchio_model(description, plant)
        if self.model.frames[self.model.getFrameId(base_link)].parentJoint != 1:
            raise PlatformModelError(f"{description}: '{base_link}' is not the root link of the first URDF")
        self.data = self.model.createData()
        joint = {name: self.model.joints[self.model.getJointId(name)] for name in list(arm_joints) + list(wheel_joints)}
        #: per arm joint, its position's and velocity's index in q and v
        self.arm_q = np.array([joint[j].idx_q for j in arm_joints], dtype=np.int64)
        self.arm_v = np.array([joint[j].idx_v for j in arm_joints], dtype=np.int64)
        #: per wheel, the index of its (cos, sin) pair in q and of its rate in v
        self.wheel_q = np.array([joint[j].idx_q for j in wheel_joints], dtype=np.int64)
        self.wheel_v = np.array([joint[j].idx_v for j in wheel_joints], dtype=np.int64)
        self.q = pin.neutral(self.model)
        self.v = np.zeros(self.model.nv)
        self.a = np.zeros(self.model.nv)

    def set_gravity(self, gravity) -> None:
        """The gravity vector (world)."""
        self.model.gravity.linear[:] = np.asarray(gravity, dtype=float)

    def mass_matrix(self) -> np.ndarray:
        """M(q) (CRBA): a new array, symmetric."""
        return pin.crba(self.model, self.data, self.q)

    def inverse_dynamics(self) -> np.ndarray:
        """M(q) a + C(q, v) v - tau_g(q) (RNEA): a new array."""
        return pin.rnea(self.model, self.data, self.q, self.v, self.a)

    def mass_properties(self, q_arm) -> MassProperties:
        """(m, d, I, lateral) of the whole robot with the arm at q_arm, base_link upright."""
        self.q[self.arm_q] = q_arm
        return MassProperties(*planar_mass_properties(self.mass_matrix(), 0))
