"""The cart controller's control model (world/platform_dynamics.py): Pinocchio's mass matrix
and inverse dynamics of TWIL + WAM, built from the robot's URDFs, against Drake's
CalcMassMatrix and CalcInverseDynamics of the plant built from the same description (the
oracle), state by state in each library's own coordinates."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import MultibodyForces

from twil_control.control.platform_model import planar_mass_properties
from twil_control.nodes.controllers.cart_linearizing import ARM_JOINTS
from twil_control.world import models
from twil_control.world.platform_dynamics import PlatformMassModel, PlatformModelError

WHEELS = ["right_wheel_joint", "left_wheel_joint"]
REL = 1e-9  # relative to the largest entry of Drake's result


@pytest.fixture(scope="module")
def model():
    return PlatformMassModel("twil_wam", ARM_JOINTS, WHEELS)


def drake_state(rng, plant):
    """A random state in Drake's layout: any base orientation, a base anywhere within 5 m, joint
    angles over several turns, and random velocities."""
    nq, nv = plant.num_positions(), plant.num_velocities()
    x = np.empty(nq + nv)
    quat = rng.normal(size=4)
    x[:4] = quat / np.linalg.norm(quat)
    x[4:7] = rng.uniform(-5.0, 5.0, 3)
    x[7:nq] = rng.uniform(-7.0, 7.0, nq - 7)
    x[nq:] = rng.normal(scale=2.0, size=nv)
    return x


def as_pinocchio(model, context, vdot):
    """(q, v, a, J) in Pinocchio's coordinates for Drake's state in `context` and accelerations
    vdot, and J with v_drake = J v_pinocchio, read through Drake's own kinematics."""
    plant = model.plant
    base = plant.GetBodyByName("base_link")
    X = base.EvalPoseInWorld(context)
    V = base.EvalSpatialVelocityInWorld(context)
    R = X.rotation().matrix()
    w_B, v_B = R.T @ V.rotational(), R.T @ V.translational()
    pm = model.model
    q, v, a = pin.neutral(pm), np.zeros(pm.nv), np.zeros(pm.nv)
    q[:3] = X.translation()
    q[3:7] = pin.Quaternion(R).coeffs()  # x, y, z, w
    v[:3], v[3:6] = v_B, w_B
    bq, bv = base.floating_positions_start(), base.floating_velocities_start_in_v()
    alpha_W, a_W = vdot[bv:bv + 3], vdot[bv + 3:bv + 6]
    a[:3], a[3:6] = R.T @ a_W - np.cross(w_B, v_B), R.T @ alpha_W
    J = np.zeros((plant.num_velocities(), pm.nv))
    J[bv:bv + 3, 3:6], J[bv + 3:bv + 6, 0:3] = R, R
    for name in ARM_JOINTS + WHEELS:
        dj, pj = plant.GetJointByName(name), pm.joints[pm.getJointId(name)]
        angle = plant.GetPositions(context)[dj.position_start()]
        if pj.nq == 2:
            q[pj.idx_q:pj.idx_q + 2] = np.cos(angle), np.sin(angle)
        else:
            q[pj.idx_q] = angle
        v[pj.idx_v] = plant.GetVelocities(context)[dj.velocity_start()]
        a[pj.idx_v] = vdot[dj.velocity_start()]
        J[dj.velocity_start(), pj.idx_v] = 1.0
    return q, v, a, J


def test_control_model_is_the_plants_robot(model):
    pm = model.model
    assert (pm.nq, pm.nv) == (18, 15)  # free base (7 / 6), two continuous wheels (2 / 1 each), 7 arm joints
    plant = model.plant
    total = sum(plant.get_body(b).default_mass() for b in plant.GetBodyIndices(plant.GetModelInstanceByName("twil")))
    total += sum(plant.get_body(b).default_mass() for b in plant.GetBodyIndices(plant.GetModelInstanceByName("wam")))
    assert sum(i.mass for i in pm.inertias) == pytest.approx(total, rel=1e-14)


def test_mass_matrix_and_inverse_dynamics_equal_drakes_on_250_random_states(model):
    rng = np.random.default_rng(3)
    plant = model.plant
    context = plant.CreateDefaultContext()
    forces = MultibodyForces(plant)
    worst_M = worst_tau = 0.0
    for _ in range(250):
        plant.SetPositionsAndVelocities(context, drake_state(rng, plant))
        vdot = rng.normal(scale=3.0, size=plant.num_velocities())
        M_ref = plant.CalcMassMatrix(context)
        plant.CalcForceElementsContribution(context, forces)
        tau_ref = plant.CalcInverseDynamics(context, vdot, forces)
        model.q[:], model.v[:], model.a[:], J = as_pinocchio(model, context, vdot)
        M, tau = model.mass_matrix(), model.inverse_dynamics()
        # M_pin = J^T M_drake J; generalised forces map the same way: tau_pin = J^T tau_drake
        worst_M = max(worst_M, np.abs(M - J.T @ M_ref @ J).max() / np.abs(M_ref).max())
        worst_tau = max(worst_tau, np.abs(tau - J.T @ tau_ref).max() / np.abs(tau_ref).max())
    assert worst_M < REL and worst_tau < REL, (worst_M, worst_tau)  # measured ~1e-15


def test_mass_properties_equal_drakes_spatial_inertia_of_the_bodies(model):
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
        expected = (S.get_mass(), c[0], I_com[2, 2], c[1])
        assert model.mass_properties(q_arm) == pytest.approx(expected, rel=1e-12, abs=1e-14)


def test_gravity_follows_the_plants(model):
    try:
        model.set_gravity([0.3, -0.2, -9.7])
        model.q[:], model.v[:], model.a[:] = pin.neutral(model.model), 0.0, 0.0
        tau = model.inverse_dynamics()
        m = planar_mass_properties(model.mass_matrix(), 0)[0]
        np.testing.assert_allclose(tau[:3], -m * np.array([0.3, -0.2, -9.7]), rtol=1e-12)  # holds the robot up
    finally:
        model.set_gravity([0.0, 0.0, -9.81])


def _plant_description(tmp_path, edit) -> str:
    """twil_wam with `edit` applied to its wam.urdf text, as a directives file in tmp_path."""
    from twil_control import PACKAGE_ROOT
    urdf = (PACKAGE_ROOT / "sim/robots/wam/wam.urdf").read_text()
    (tmp_path / "wam.urdf").write_text(edit(urdf))
    dmd = (PACKAGE_ROOT / "sim/robots/twil_wam.dmd.yaml").read_text()
    dmd = dmd.replace("package://twil_control/sim/robots/wam/wam.urdf", "file://" + str(tmp_path / "wam.urdf"))
    dmd = dmd.replace("package://twil_control/sim/robots/twil/twil.urdf",
                      "file://" + str(PACKAGE_ROOT / "sim/robots/twil/twil.urdf"))
    (tmp_path / "robot.dmd.yaml").write_text(dmd)
    return str(tmp_path / "robot.dmd.yaml")


def test_what_the_control_model_does_not_hold_is_refused(tmp_path):
    damped = _plant_description(tmp_path, lambda text: text.replace(
        '<joint name="wam_joint_2" type="revolute">', '<joint name="wam_joint_2" type="revolute">'
        '<dynamics damping="0.5"/>', 1))
    with pytest.raises(PlatformModelError, match="wam_joint_2.*damping"):
        PlatformMassModel(damped, ARM_JOINTS, WHEELS)
    with pytest.raises(PlatformModelError, match="not joints of the description"):
        PlatformMassModel("twil_wam", ARM_JOINTS[:-1] + ["wam_joint_9"], WHEELS)
    with pytest.raises(PlatformModelError, match="is not a free body"):
        PlatformMassModel("wam_fixed", ARM_JOINTS, [], base_link="wam_base_link")
