"""control/rigid_body_kernel.py (compiled mass matrix and inverse dynamics) against Drake's
CalcMassMatrix and CalcInverseDynamics (with gravity from CalcForceElementsContribution), on the
whole TWIL + WAM tree that world/platform_dynamics.kernel_tree extracts from the plant."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import MultibodyForces

from twil_control.control import rigid_body_kernel as rbk
from twil_control.controllers.cart_linearizing import ARM_JOINTS
from twil_control.world import models
from twil_control.world.platform_dynamics import PlatformMassModel, PlatformModelError, kernel_tree

pytestmark = pytest.mark.kernels

WHEELS = ["right_wheel_joint", "left_wheel_joint"]
REL = 1e-9  # relative to the largest entry of Drake's result


@pytest.fixture(scope="module")
def model():
    return PlatformMassModel("twil_wam", ARM_JOINTS, WHEELS)


def random_state(rng, plant):
    """A random state in Drake's layout: any base orientation (not only yaw), a base anywhere
    within 5 m, joint angles over several turns, and random velocities."""
    nq, nv = plant.num_positions(), plant.num_velocities()
    x = np.empty(nq + nv)
    quat = rng.normal(size=4)
    x[:4] = quat / np.linalg.norm(quat)
    x[4:7] = rng.uniform(-5.0, 5.0, 3)
    x[7:nq] = rng.uniform(-7.0, 7.0, nq - 7)
    x[nq:] = rng.normal(scale=2.0, size=nv)
    return x


def drake_dynamics(plant, context, x, vdot):
    plant.SetPositionsAndVelocities(context, x)
    forces = MultibodyForces(plant)
    plant.CalcForceElementsContribution(context, forces)
    return plant.CalcMassMatrix(context), plant.CalcInverseDynamics(context, vdot, forces)


def relative_errors(tree, plant, context, rng, states):
    """The largest relative error of M and of tau over `states` random states."""
    nv = plant.num_velocities()
    work, M, tau = rbk.work_array(tree.tree.shape[0]), np.zeros((nv, nv)), np.zeros(nv)
    worst_M = worst_tau = 0.0
    for _ in range(states):
        x = random_state(rng, plant)
        vdot = rng.normal(scale=3.0, size=nv)
        M_ref, tau_ref = drake_dynamics(plant, context, x, vdot)
        rbk.dynamics(tree.tree, tree.extra, x, vdot, work, M, tau)
        worst_M = max(worst_M, np.abs(M - M_ref).max() / np.abs(M_ref).max())
        worst_tau = max(worst_tau, np.abs(tau - tau_ref).max() / np.abs(tau_ref).max())
    return worst_M, worst_tau


def test_tree_has_the_robots_ten_moving_bodies(model):
    tree = model.kernel
    assert tree.names[0] == "base_link" and len(tree.names) == 10  # base, 2 wheels, 7 arm links
    assert set(tree.names[1:]) == {
        "left_wheel_link",
        "right_wheel_link",
        "wam_link_1",
        "wam_link_2",
        "wam_link_3_virtual",
        "wam_link_4_virtual",
        "wam_link_5",
        "wam_link_6",
        "wam_link_7",
    }
    parents = tree.tree[:, rbk.TREE_PARENT]
    assert parents[0] == -1 and all(0 <= p < k for k, p in enumerate(parents) if k)
    # every body's mass is in some node (welded mount and WAM base folded into base_link)
    plant = model.plant
    total = sum(
        plant.get_body(b).default_mass()
        for name in ("twil", "wam")
        for b in plant.GetBodyIndices(plant.GetModelInstanceByName(name))
    )
    assert tree.tree[:, rbk.TREE_MASS].sum() == pytest.approx(total, rel=1e-14)


def test_mass_matrix_and_inverse_dynamics_equal_drakes_on_250_random_states(model):
    worst_M, worst_tau = relative_errors(
        model.kernel, model.plant, model.plant.CreateDefaultContext(), np.random.default_rng(3), 250
    )
    assert worst_M < REL and worst_tau < REL, (worst_M, worst_tau)  # measured ~2e-14 and ~1e-14


def test_model_dynamics_reads_its_state_and_gravity(model):
    rng = np.random.default_rng(5)
    plant = model.plant
    context = plant.CreateDefaultContext()
    try:
        model.set_gravity([0.3, -0.2, -9.7])
        plant.mutable_gravity_field().set_gravity_vector([0.3, -0.2, -9.7])
        for _ in range(20):
            model.x[:] = random_state(rng, plant)
            model.vdot[:] = rng.normal(scale=3.0, size=model.vdot.size)
            M_ref, tau_ref = drake_dynamics(plant, context, model.x, model.vdot)
            M, tau = model.dynamics()
            assert np.abs(M - M_ref).max() <= REL * np.abs(M_ref).max()
            assert np.abs(tau - tau_ref).max() <= REL * np.abs(tau_ref).max()
    finally:
        model.set_gravity([0.0, 0.0, -9.81])
        plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, -9.81])


def test_mass_properties_equal_drakes_spatial_inertia_of_the_bodies(model):
    """(m, d, I, lateral) read off the kernel's mass matrix (platform_model.planar_mass_properties)
    against Drake's CalcSpatialInertia of the robot's bodies about base_link."""
    plant = model.plant
    context = plant.CreateDefaultContext()
    bodies = [b for name in ("twil", "wam") for b in plant.GetBodyIndices(plant.GetModelInstanceByName(name))]
    rng = np.random.default_rng(4)
    for _ in range(20):
        q_arm = rng.uniform(-2.5, 2.5, 7)
        q = plant.GetPositions(context)
        for name, value in zip(ARM_JOINTS, q_arm):
            q[plant.GetJointByName(name).position_start()] = value
        plant.SetPositions(context, q)
        S = plant.CalcSpatialInertia(context, plant.GetBodyByName("base_link").body_frame(), bodies)
        c = S.get_com()
        I_com = S.Shift(c).CalcRotationalInertia().CopyToFullMatrix3()
        assert model.mass_properties(q_arm) == pytest.approx(
            (S.get_mass(), c[0], I_com[2, 2], c[1]), rel=1e-12, abs=1e-14
        )


@pytest.mark.parametrize("node", range(1, 10))
def test_a_flipped_joint_axis_is_detected(model, node):
    tree = model.kernel
    wrong = type(tree)(tree.tree.copy(), tree.extra.copy(), tree.names)
    wrong.tree[node, rbk.TREE_AXIS : rbk.TREE_AXIS + 3] *= -1.0
    worst_M, worst_tau = relative_errors(
        wrong, model.plant, model.plant.CreateDefaultContext(), np.random.default_rng(node), 3
    )
    # fails the comparison by far: measured 2e-6 (wrist link 7, 0.07 kg), 3e-5 to 1e-4 (wheels), 3e-4 to 0.3 (arm)
    assert max(worst_M, worst_tau) > 100 * REL, (tree.names[node], worst_M, worst_tau)


def test_a_misplaced_joint_is_detected(model):
    tree = model.kernel
    wrong = type(tree)(tree.tree.copy(), tree.extra.copy(), tree.names)
    wrong.tree[5, rbk.TREE_P] += 0.01  # 1 cm
    assert (
        max(
            relative_errors(
                wrong, model.plant, model.plant.CreateDefaultContext(), np.random.default_rng(1), 3
            )
        )
        > 100 * REL
    )


def _plant(edit):
    """twil_wam in a continuous plant, `edit(plant)` applied before Finalize()."""
    plant = MultibodyPlant(time_step=0.0)
    models.add_model(plant, "twil_wam")
    edit(plant)
    plant.Finalize()
    return plant


def test_reflected_rotor_inertia_is_on_the_diagonal_as_in_drake():
    def rotors(plant):
        for k, name in enumerate(ARM_JOINTS + WHEELS):
            actuator = plant.GetJointActuatorByName(name)
            actuator.set_default_rotor_inertia(1e-4 * (k + 1))
            actuator.set_default_gear_ratio(10.0 + k)

    plant = _plant(rotors)
    context = plant.CreateDefaultContext()
    tree = kernel_tree(plant, context)
    assert np.count_nonzero(tree.extra[:-3]) == 9
    worst = relative_errors(tree, plant, context, np.random.default_rng(8), 20)
    assert max(worst) < REL, worst


def test_what_the_kernel_does_not_model_is_refused():
    damped = _plant(lambda p: p.GetJointByName("wam_joint_2").set_default_damping(0.5))
    with pytest.raises(PlatformModelError, match="wam_joint_2.*damping"):
        kernel_tree(damped, damped.CreateDefaultContext())
    weightless = _plant(
        lambda p: p.mutable_gravity_field().set_enabled(p.GetModelInstanceByName("wam"), False)
    )
    with pytest.raises(PlatformModelError, match="gravity is disabled.*wam"):
        kernel_tree(weightless, weightless.CreateDefaultContext())
