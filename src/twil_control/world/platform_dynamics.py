"""The TWIL platform's mass properties from its description, for K5..K8 of (14)-(15).

`PlatformMassModel` parses the whole robot (TWIL with the WAM on its mount, the description the
simulated plant is built from) into its own plant, whose mass matrix gives the planar rigid-body
data of platform_model.derive_constants; the definitions and assumptions are in
docs/cart_controller.md. For the 1 kHz update it holds the kinematic tree in
control/rigid_body_kernel.py's arrays (`kernel_tree`), with Drake's dynamics as the test oracle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JointIndex, ModelInstanceIndex

from twil_control.control import rigid_body_kernel as rbk
from twil_control.control.platform_model import planar_mass_properties
from twil_control.errors import TwilControlError

from . import models

__all__ = ["PlatformMassModel", "PlatformModelError", "MassProperties", "KernelTree", "kernel_tree"]


class PlatformModelError(TwilControlError, ValueError):
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


@dataclass
class KernelTree:
    """A plant's kinematic tree in control.rigid_body_kernel's arrays (layout: the TREE_* comment there)."""

    tree: np.ndarray  # (nodes, rbk.TREE_WIDTH)
    extra: np.ndarray  # reflected inertia per velocity, then gravity
    names: list[str]  # each node's body (the child body of its joint)

    def set_gravity(self, gravity) -> None:
        self.extra[-3:] = gravity


def kernel_tree(plant: MultibodyPlant, context) -> KernelTree:
    """The finalized `plant` as control.rigid_body_kernel's tree: one free body (Drake's
    quaternion floating joint, from the world frame to its body frame), revolute joints below
    it, welds folded into the body they are welded to. Refuses (PlatformModelError) anything
    the kernel does not model: other joint types, joint damping, force elements other than
    gravity, gravity disabled for a model instance, several free bodies."""
    joints = [plant.get_joint(JointIndex(i)) for i in range(plant.num_joints())]
    _check_kernel_models(plant, joints)
    root = _free_joint(plant, joints)
    node_joints, node_of, bodies_of = _nodes_below(plant, joints, root)
    tree = np.zeros((len(node_joints), rbk.TREE_WIDTH))
    for k, j in enumerate(node_joints):
        _fill_tree_row(tree[k], plant, context, k, j, node_joints, node_of, bodies_of[k])
    extra = np.zeros(plant.num_velocities() + 3)
    for a in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(a)
        extra[actuator.joint().velocity_start()] += actuator.default_reflected_inertia()
    extra[-3:] = plant.gravity_field().gravity_vector()
    return KernelTree(
        tree,
        extra,
        [plant.get_body(node_joints[k].child_body().index()).name() for k in range(len(node_joints))],
    )


def _check_kernel_models(plant: MultibodyPlant, joints: list) -> None:
    """Refuse joint types, damping and force elements the kernel does not model."""
    for j in joints:
        if j.type_name() not in ("revolute", "weld", "quaternion_floating"):
            raise PlatformModelError(
                f"joint '{j.name()}' is a {j.type_name()} joint: the dynamics kernel takes "
                "revolute and weld joints below one quaternion floating joint"
            )
        if np.any(np.asarray(j.default_damping_vector()) != 0.0):
            raise PlatformModelError(
                f"joint '{j.name()}' has damping {j.default_damping_vector()}: "
                "the dynamics kernel models none"
            )
    if plant.num_force_elements() != 1:
        raise PlatformModelError(
            f"{plant.num_force_elements() - 1} force elements besides gravity: "
            "the dynamics kernel models gravity only"
        )
    gravity = plant.gravity_field()
    for k in range(plant.num_model_instances()):
        if not gravity.is_enabled(ModelInstanceIndex(k)):
            raise PlatformModelError(
                f"gravity is disabled for model instance "
                f"'{plant.GetModelInstanceName(ModelInstanceIndex(k))}'"
            )


def _free_joint(plant: MultibodyPlant, joints: list):
    """The one quaternion floating joint, from the world frame to its body's frame."""
    free = [j for j in joints if j.type_name() == "quaternion_floating"]
    if len(free) != 1:
        raise PlatformModelError(f"{len(free)} free bodies: the dynamics kernel takes exactly one")
    root = free[0]
    if (
        root.parent_body().index() != plant.world_body().index()
        or root.frame_on_parent().index() != plant.world_frame().index()
        or root.frame_on_child().index() != root.child_body().body_frame().index()
    ):
        raise PlatformModelError(
            f"free joint '{root.name()}' is not between the world frame and its body's frame"
        )
    return root


def _nodes_below(plant: MultibodyPlant, joints: list, root) -> tuple[list, dict, list[list]]:
    """(the nodes' joints, body -> node, node -> bodies), breadth first from the free body:
    parents before children; welded bodies join their parent's node."""
    below: dict = {}
    for j in joints:
        below.setdefault(j.parent_body().index(), []).append(j)
    node_joints, node_of, bodies_of = [root], {root.child_body().index(): 0}, [[root.child_body().index()]]
    queue = [root.child_body().index()]
    while queue:
        body = queue.pop(0)
        for j in below.get(body, []):
            child = j.child_body().index()
            if j.type_name() == "weld":
                node_of[child] = node_of[body]
            else:
                node_of[child] = len(node_joints)
                node_joints.append(j)
                bodies_of.append([])
            bodies_of[node_of[child]].append(child)
            queue.append(child)
    if len(node_of) != plant.num_bodies() - 1:
        raise PlatformModelError(
            "bodies not attached below the free body: the dynamics kernel takes one tree"
        )
    return node_joints, node_of, bodies_of


def _fill_tree_row(row, plant: MultibodyPlant, context, k: int, j, node_joints, node_of, bodies) -> None:
    """Node k's row: its joint's coordinates, parent, fixed pose in the parent node's frame and
    axis, and the spatial inertia of its bodies about its frame's origin."""
    frame = j.frame_on_child()  # the node's frame M
    row[rbk.TREE_Q], row[rbk.TREE_V] = j.position_start(), j.velocity_start()
    if k == 0:
        row[rbk.TREE_PARENT] = -1
        row[rbk.TREE_R : rbk.TREE_R + 9] = np.eye(3).ravel()
    else:
        parent = node_of[j.parent_body().index()]
        row[rbk.TREE_PARENT] = parent
        # F in the parent node's frame (through welds only: the same at any state)
        X = plant.CalcRelativeTransform(context, node_joints[parent].frame_on_child(), j.frame_on_parent())
        row[rbk.TREE_R : rbk.TREE_R + 9] = X.rotation().matrix().ravel()
        row[rbk.TREE_P : rbk.TREE_P + 3] = X.translation()
        row[rbk.TREE_AXIS : rbk.TREE_AXIS + 3] = j.revolute_axis()
    inertia = plant.CalcSpatialInertia(context, frame, bodies)  # about M's origin, in M
    row[rbk.TREE_MASS] = inertia.get_mass()
    row[rbk.TREE_COM : rbk.TREE_COM + 3] = inertia.get_com()
    row[rbk.TREE_INERTIA : rbk.TREE_INERTIA + 9] = inertia.CalcRotationalInertia().CopyToFullMatrix3().ravel()


class PlatformMassModel:
    """The robot's control model (module docstring): the Drake `plant` it was checked and
    extracted from, the compiled `kernel` tree, and the arrays the compiled update works in:
    the state `x` (Drake's positions then velocities, see `layout`), `vdot`, `M`, `tau` and the
    kernel's `work`."""

    def __init__(
        self, description: str, arm_joints: list[str], wheel_joints: list[str], base_link: str = "base_link"
    ) -> None:
        plant = MultibodyPlant(time_step=0.0)
        try:
            models.add_model(plant, description, parser=Parser(plant))
        except models.ModelError as error:
            raise PlatformModelError(str(error)) from error
        plant.Finalize()
        self.plant = plant
        if not plant.HasBodyNamed(base_link):
            raise PlatformModelError(f"{description}: no link '{base_link}'")
        base = plant.GetBodyByName(base_link)
        missing = [j for j in list(arm_joints) + list(wheel_joints) if not plant.HasJointNamed(j)]
        if missing:
            raise PlatformModelError(
                f"{description}: joints {', '.join(missing)} are not joints of the description"
            )
        if not base.is_floating_base_body():
            raise PlatformModelError(f"{description}: '{base_link}' is not a free body")
        wheel_Iw = []
        for j in wheel_joints:
            joint = plant.GetJointByName(j)
            axis = (
                np.asarray(joint.revolute_axis())
                if hasattr(joint, "revolute_axis")
                else np.array([0, 1.0, 0])
            )
            I = joint.child_body().default_rotational_inertia().CopyToFullMatrix3()
            wheel_Iw.append(float(axis @ I @ axis))
        self.wheel_inertia = float(np.mean(wheel_Iw)) if wheel_Iw else 0.0
        context = plant.CreateDefaultContext()
        self.kernel = kernel_tree(plant, context)
        nq, nv = plant.num_positions(), plant.num_velocities()
        self._nq = nq
        self._base_q = base.floating_positions_start()
        self._base_v = base.floating_velocities_start_in_v()
        self._arm_q = np.array([plant.GetJointByName(j).position_start() for j in arm_joints])
        self._arm_v = np.array([plant.GetJointByName(j).velocity_start() for j in arm_joints])
        self.x = plant.GetPositionsAndVelocities(context).copy()
        self.vdot = np.zeros(nv)
        self.work = rbk.work_array(self.kernel.tree.shape[0])
        self.M = np.zeros((nv, nv))
        self.tau = np.zeros(nv)

    def set_gravity(self, gravity) -> None:
        """The gravity vector (world)."""
        self.kernel.set_gravity(gravity)

    @property
    def layout(self) -> tuple[np.ndarray, int, int, np.ndarray, np.ndarray]:
        """(x, q_base, v_base, arm_q, arm_v): the state vector x (positions then velocities),
        where the base's 7 positions and 6 velocities start in it, and the arm joints' indices
        in it; write x in place. v_base - num_positions is the base's index in the generalised
        velocities (and accelerations)."""
        nq = self._nq
        return self.x, self._base_q, nq + self._base_v, self._arm_q, nq + self._arm_v

    def dynamics(self) -> tuple[np.ndarray, np.ndarray]:
        """(M, M vdot + C v - tau_g) at the state `x` for the accelerations `vdot` (the compiled
        kernel, one kinematics pass); both arrays are reused by the next call."""
        rbk.dynamics(self.kernel.tree, self.kernel.extra, self.x, self.vdot, self.work, self.M, self.tau)
        return self.M, self.tau

    def mass_properties(self, q_arm) -> MassProperties:
        """(m, d, I, lateral) of the whole robot with the arm at q_arm, base_link upright at yaw 0."""
        self.x[self._base_q : self._base_q + 7] = (1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        self.x[self._arm_q] = q_arm
        M, _ = self.dynamics()
        return MassProperties(*planar_mass_properties(M, self._base_v, 0.0))
