"""control/cart_kernel.py, the cart controller's compiled update, against its equations and an
independent oracle: each update's outputs are recomputed from the one implementation of each
equation (backstepping.command, platform_model, diff_odometry, trajectory, computed_torque),
with the mass properties and the arm's torques taken from Drake's plant of the same robot
(CalcSpatialInertia, CalcInverseDynamics) instead of Pinocchio's model the update uses."""
from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.tree import MultibodyForces

from twil_control.control import cart_kernel as ck
from twil_control.control.backstepping import CORRECTED, PRINTED, command
from twil_control.control.computed_torque import commanded_acceleration
from twil_control.control.diff_odometry import odometry_step
from twil_control.control.gains import GAIN_NAMES
from twil_control.control.platform_model import constants, feedback_linearization, saturate_pair, \
    wheel_velocities_to_body
from twil_control.control.trajectory import held_reference
from twil_control.nodes.controllers.cart_linearizing import ARM_JOINTS
from twil_control.world.platform_dynamics import PlatformMassModel

GAINS = dict(gamma1=0.4, gamma2=1.0, gamma4=3.0, gamma5=3.0, lambda1=0.5, lambda2=1.0, lambda3=2.0,
             lambda4=1.0, lambda5=1.0)
G = np.array([GAINS[k] for k in GAIN_NAMES])
R, B = 0.075, 0.161
WHEELS = ["right_wheel_joint", "left_wheel_joint"]


@pytest.fixture(scope="module")
def model():
    return PlatformMassModel("twil_wam", ARM_JOINTS, WHEELS)


def drake_oracle(model, base_pose: RigidTransform, w_W, v_W, position, velocity, arm_hw, alpha_W, a_W, arm_acc):
    """(m, d, I, lateral) about base_link and the arm rows of M vdot + C v - tau_g, from Drake."""
    plant = model.plant
    context = plant.CreateDefaultContext()
    base = plant.GetBodyByName("base_link")
    plant.SetFreeBodyPose(context, base, base_pose)
    from pydrake.multibody.math import SpatialVelocity
    plant.SetFreeBodySpatialVelocity(context, base, SpatialVelocity(w_W, v_W))
    vdot = np.zeros(plant.num_velocities())
    bv = base.floating_velocities_start_in_v()
    vdot[bv:bv + 3], vdot[bv + 3:bv + 6] = alpha_W, a_W
    for k, name in enumerate(ARM_JOINTS):
        joint = plant.GetJointByName(name)
        joint.set_angle(context, position[arm_hw[k]])
        joint.set_angular_rate(context, velocity[arm_hw[k]])
        vdot[joint.velocity_start()] = arm_acc[k]
    for name, hw in zip(WHEELS, (0, 1)):
        plant.GetJointByName(name).set_angular_rate(context, velocity[hw])
    bodies = [b for n in ("twil", "wam") for b in plant.GetBodyIndices(plant.GetModelInstanceByName(n))]
    S = plant.CalcSpatialInertia(context, base.body_frame(), bodies)
    c = S.get_com()
    mass = (S.get_mass(), c[0], S.Shift(c).CalcRotationalInertia().CopyToFullMatrix3()[2, 2], c[1])
    forces = MultibodyForces(plant)
    plant.CalcForceElementsContribution(context, forces)
    tau = plant.CalcInverseDynamics(context, vdot, forces)
    return mass, np.array([tau[plant.GetJointByName(n).velocity_start()] for n in ARM_JOINTS])


@pytest.mark.parametrize("law", [CORRECTED, PRINTED])
def test_update_equals_its_equations_with_drakes_dynamics(model, law):
    rng = np.random.default_rng(13 + law)
    n = 7
    arm_hw = np.arange(2, 9)  # the hardware's arrays: right wheel, left wheel, then the arm
    kp, kd = rng.uniform(5, 30, n), rng.uniform(1, 10, n)
    timeout, tolerance = 0.1, 0.003
    params = ck.step_params(R, B, model.wheel_inertia, 6.0, tolerance, timeout, law, None, G, kp, kd)
    plant = model.plant
    base_body = plant.GetBodyByName("base_link")
    plant_q = base_body.floating_positions_start()
    plant_v = plant.num_positions() + base_body.floating_velocities_start_in_v()
    index = ck.step_index([0, 1], model.wheel_q, model.wheel_v, plant_q, plant_v, model.arm_q, model.arm_v, arm_hw)
    out, inp, effort = np.zeros(ck.out_size(n)), np.zeros(ck.IN_SIZE), np.zeros(9)
    plant_state = np.zeros(plant.num_multibody_states())
    saturated = braked = 0
    for k in range(120):
        planar = k % 2 == 0
        position, velocity = rng.uniform(-2, 2, 9), rng.uniform(-2, 2, 9)
        ref = rng.uniform(-3, 3, 3)
        q_s, qd_s, qdd_s = (rng.uniform(-1.5, 1.5, n) for _ in range(3))
        age = [-0.01, 0.0, 0.03, 0.5][k % 4]
        limit = params[ck.P_LIMIT] = [math.inf, 60.0, 0.5][k % 3]
        inp[:] = [0, 0, 0, *ref, age, 1.0 if planar else 0.0]
        odo = np.concatenate([rng.uniform(-3, 3, 3), position[[1, 0]] - rng.normal(0, 0.01, 2), [1.0]])
        odo_expected = odo.copy()
        u1, u2 = wheel_velocities_to_body(velocity[0], velocity[1], R, B)
        if planar:
            odometry_step(odo_expected, position[1], position[0], R, 2 * B)
            x, y, yaw = odo_expected[:3]
            X = RigidTransform(RotationMatrix.MakeZRotation(yaw), [x, y, 0.0])
            w_W, v_W = np.array([0.0, 0.0, u2]), np.array([u1 * math.cos(yaw), u1 * math.sin(yaw), 0.0])
        else:  # the simulator's base, tilted and moving in 3D
            quat = rng.normal(size=4)
            quat /= np.linalg.norm(quat)
            p = rng.uniform(-3, 3, 3)
            w_W, v_W = rng.normal(size=3), rng.normal(size=3)
            plant_state[plant_q:plant_q + 7] = [*quat, *p]
            plant_state[plant_v:plant_v + 6] = [*w_W, *v_W]
            Rm = RotationMatrix(np.array(_quat_matrix(quat)))
            X = RigidTransform(Rm, p)
            x, y = p[:2]
            yaw = math.atan2(Rm.matrix()[1, 0], Rm.matrix()[0, 0])
        ck.cart_state(inp, params, index, position, velocity, plant_state, q_s, qd_s, qdd_s, odo, model.q, model.v,
                      out)
        M = model.mass_matrix()
        ck.cart_command(inp, params, index, M, out, model.a)
        tau = model.inverse_dynamics()
        ck.write_efforts(index, out, tau, effort)
        # the pose, u and the held reference
        np.testing.assert_allclose(inp[:3], [x, y, yaw], rtol=1e-14, atol=1e-14)
        assert np.array_equal(odo, odo_expected)
        assert tuple(out[ck.OUT_U:ck.OUT_U + 2]) == (u1, u2)
        held = held_reference(q_s, qd_s, qdd_s, age, timeout)
        assert np.array_equal(out[ck.OUT_REF:ck.OUT_REF + 3 * n], np.concatenate(held))
        # the law, K5..K8 from Drake's mass properties, the linearisation and the saturation
        v = command(law, x, y, yaw, *ref, u1, u2, G, tolerance)
        braked += v == (-3.0 * u1, -3.0 * u2)
        arm_acc = commanded_acceleration(position[arm_hw], velocity[arm_hw], *held, kp, kd, np.zeros(n))
        scale = out[ck.OUT_SCALE]
        Rm = X.rotation().matrix()
        w_B, v_B = Rm.T @ w_W, Rm.T @ v_W
        a_B, alpha_B = np.array([scale * v[0], 0, 0]), np.array([0, 0, scale * v[1]])
        (m, d, inertia, _), arm_tau = drake_oracle(model, X, w_W, v_W, position, velocity, arm_hw, Rm @ alpha_B,
                                                   Rm @ (a_B + np.cross(w_B, v_B)), arm_acc)
        K = constants(m, inertia, d, R, B, model.wheel_inertia, 1.0)
        tau_raw = feedback_linearization(*v, u1, u2, *K)
        tau_r, tau_l, s = saturate_pair(*tau_raw, limit)
        saturated += s < 1.0
        np.testing.assert_allclose(out[ck.OUT_V:ck.OUT_V + 2], v, rtol=1e-12)  # the yaw from R differs by ulps
        np.testing.assert_allclose(out[ck.OUT_K:ck.OUT_K + 4], K, rtol=1e-10)
        np.testing.assert_allclose(out[ck.OUT_TAU_RAW:ck.OUT_TAU_RAW + 2], tau_raw, rtol=1e-9)
        np.testing.assert_allclose([*out[ck.OUT_TAU:ck.OUT_TAU + 2], scale], [tau_r, tau_l, s], rtol=1e-9)
        assert tuple(effort[:2]) == tuple(out[ck.OUT_TAU:ck.OUT_TAU + 2])
        np.testing.assert_allclose(effort[arm_hw], arm_tau, rtol=1e-9, atol=1e-9 * np.abs(arm_tau).max())
    assert 10 < saturated < 110 and braked == 0  # both saturation branches, the law itself (not the brake)


def _quat_matrix(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def test_given_constants_replace_the_derived_ones(model):
    """With constants given (the lab's identified K5..K8, say), the mass matrix is not read."""
    n = 7
    given = (0.0844476, 3.770688, 2.646890, 16.084061)
    params = ck.step_params(R, B, model.wheel_inertia, math.inf, 0.003, 0.1, CORRECTED, given, G, np.full(n, 25.0),
                            np.full(n, 10.0))
    index = ck.step_index([0, 1], model.wheel_q, model.wheel_v, 0, 0, model.arm_q, model.arm_v, np.arange(2, 9))
    out, inp = np.zeros(ck.out_size(n)), np.array([0, 0, 0, 1.0, 0.5, 0.2, 0.0, 1.0])
    velocity = np.array([1.0, 0.5, 0, 0, 0, 0, 0, 0, 0])
    ck.cart_state(inp, params, index, np.zeros(9), velocity, np.zeros(1), np.zeros(n), np.zeros(n), np.zeros(n),
                  np.zeros(ck.ODO_SIZE), model.q, model.v, out)
    ck.cart_command(inp, params, index, np.full((15, 15), np.nan), out, model.a)
    assert tuple(out[ck.OUT_K:ck.OUT_K + 4]) == given
    u = wheel_velocities_to_body(1.0, 0.5, R, B)
    v = command(CORRECTED, 0.0, 0.0, 0.0, 1.0, 0.5, 0.2, *u, G, 0.003)
    assert tuple(out[ck.OUT_TAU:ck.OUT_TAU + 2]) == feedback_linearization(*v, *u, *given)
