"""control/cart_kernel.py, the cart controller's compiled update, against its equations and an
independent oracle: each update's outputs are recomputed from the one implementation of each
equation (backstepping.command, platform_model, diff_odometry, trajectory, computed_torque),
with the mass properties and the arm's torques taken from Drake's plant of the same robot
(CalcSpatialInertia, CalcInverseDynamics) instead of the compiled rigid-body kernel the update
uses, and the base's planar state and acceleration written out here."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.multibody.tree import MultibodyForces

from twil_control.control import cart_kernel as ck
from twil_control.control.backstepping import CORRECTED, PRINTED, command
from twil_control.control.computed_torque import commanded_acceleration
from twil_control.control.diff_odometry import odometry_step
from twil_control.control.gains import GAIN_NAMES
from twil_control.control.platform_model import (
    constants,
    feedback_linearization,
    saturate_pair,
    wheel_velocities_to_body,
)
from twil_control.control.trajectory import held_reference
from twil_control.control.transforms import yaw_from_quat
from twil_control.controllers.cart_linearizing import ARM_JOINTS
from twil_control.world.platform_dynamics import PlatformMassModel

pytestmark = pytest.mark.kernels

GAINS = dict(
    gamma1=0.4,
    gamma2=1.0,
    gamma4=3.0,
    gamma5=3.0,
    lambda1=0.5,
    lambda2=1.0,
    lambda3=2.0,
    lambda4=1.0,
    lambda5=1.0,
)
G = np.array([GAINS[k] for k in GAIN_NAMES])
R, B = 0.075, 0.161


@pytest.fixture(scope="module")
def model():
    return PlatformMassModel("twil_wam", ARM_JOINTS, ["right_wheel_joint", "left_wheel_joint"])


def planar_base(x, y, yaw, u1, u2, u1_dot=0.0, u2_dot=0.0):
    """(q, v, vdot) of a free body in Drake's coordinates moving in the plane: the axle midpoint
    accelerates with u1_dot along the heading and u1 u2 across it."""
    c, s = math.cos(yaw), math.sin(yaw)
    q = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2), x, y, 0.0]
    v = [0.0, 0.0, u2, u1 * c, u1 * s, 0.0]
    a_long, a_lat = u1_dot, u1 * u2
    return q, v, [0.0, 0.0, u2_dot, a_long * c - a_lat * s, a_long * s + a_lat * c, 0.0]


def drake_oracle(model, x, vdot, yaw):
    """(m, d, I, lateral) of the robot and its M vdot + C v - tau_g at the state x, from Drake:
    the centre of mass and the inertia about the vertical through it, in world axes, d and lateral
    in the heading's axes."""
    plant = model.plant
    context = plant.CreateDefaultContext()
    plant.SetPositionsAndVelocities(context, x)
    bodies = [b for n in ("twil", "wam") for b in plant.GetBodyIndices(plant.GetModelInstanceByName(n))]
    S = plant.CalcSpatialInertia(context, plant.world_frame(), bodies)
    com = S.get_com()
    p = com - plant.GetBodyByName("base_link").EvalPoseInWorld(context).translation()
    c, s = math.cos(yaw), math.sin(yaw)
    inertia = S.Shift(com).CalcRotationalInertia().CopyToFullMatrix3()[2, 2]
    forces = MultibodyForces(plant)
    plant.CalcForceElementsContribution(context, forces)
    return (S.get_mass(), c * p[0] + s * p[1], inertia, -s * p[0] + c * p[1]), plant.CalcInverseDynamics(
        context, vdot, forces
    )


@pytest.mark.parametrize("law", [CORRECTED, PRINTED])
def test_update_equals_its_equations_with_drakes_dynamics(model, law):
    rng = np.random.default_rng(13 + law)
    n = 7
    x, q_base, v_base, arm_q, arm_v = model.layout
    nq = model.plant.num_positions()
    base = v_base - nq
    hw_index = rng.permutation(9)  # where the hardware keeps each joint: right, left wheel, arm
    wheels, arm_hw = hw_index[:2], hw_index[2:]
    kp, kd = rng.uniform(5, 30, n), rng.uniform(1, 10, n)
    timeout, tolerance = 0.1, 0.003
    params = ck.step_params(R, B, model.wheel_inertia, 6.0, tolerance, timeout, law, None, G, kp, kd)
    index = ck.step_index(q_base, v_base, base, wheels, arm_q, arm_v, arm_hw)
    out, inp, effort = np.zeros(ck.out_size(n)), np.zeros(ck.IN_SIZE), np.zeros(9)
    saturated = braked = 0
    for k in range(120):
        planar = k % 2 == 0
        position, velocity = rng.uniform(-2, 2, 9), rng.uniform(-2, 2, 9)
        ref = rng.uniform(-3, 3, 3)
        q_s, qd_s, qdd_s = (rng.uniform(-1.5, 1.5, n) for _ in range(3))
        age = [-0.01, 0.0, 0.03, 0.5][k % 4]
        limit = params[ck.P_LIMIT] = [math.inf, 60.0, 0.5][k % 3]
        odo = np.concatenate([rng.uniform(-3, 3, 3), position[wheels[::-1]] - rng.normal(0, 0.01, 2), [1.0]])
        odo_expected = odo.copy()
        u1, u2 = wheel_velocities_to_body(velocity[wheels[0]], velocity[wheels[1]], R, B)
        if planar:
            odometry_step(odo_expected, position[wheels[1]], position[wheels[0]], R, 2 * B)
            pose = odo_expected[:3]
            inp[:] = [0, 0, 0, *ref, age, 1.0]
        else:  # ground truth: the base's state as it is, tilted and moving in 3D
            quat = rng.normal(size=4)
            quat /= np.linalg.norm(quat)
            x[q_base : q_base + 7] = [*quat, *rng.uniform(-3, 3, 3)]
            x[v_base : v_base + 6] = rng.normal(size=6)
            pose = (x[q_base + 4], x[q_base + 5], yaw_from_quat((*quat[1:], quat[0])))
            inp[:] = [*pose, *ref, age, 0.0]
        ck.cart_step(
            inp,
            params,
            index,
            position,
            velocity,
            q_s,
            qd_s,
            qdd_s,
            odo,
            x,
            model.kernel.tree,
            model.kernel.extra,
            model.work,
            model.M,
            model.vdot,
            model.tau,
            out,
            effort,
        )
        # the pose, u, the state and the held reference
        assert np.array_equal(inp[:3], pose) and np.array_equal(odo, odo_expected)
        assert tuple(out[ck.OUT_U : ck.OUT_U + 2]) == (u1, u2)
        if planar:
            base_q, base_v, _ = planar_base(*pose, u1, u2)
            np.testing.assert_allclose(x[q_base : q_base + 7], base_q, rtol=1e-15, atol=1e-15)
            np.testing.assert_allclose(x[v_base : v_base + 6], base_v, rtol=1e-15, atol=1e-15)
        assert np.array_equal(x[arm_q], position[arm_hw]) and np.array_equal(x[arm_v], velocity[arm_hw])
        held = held_reference(q_s, qd_s, qdd_s, age, timeout)
        assert np.array_equal(out[ck.OUT_REF : ck.OUT_REF + 3 * n], np.concatenate(held))
        # the law, K5..K8 from Drake's mass properties, the linearisation, the saturation
        v = command(law, *pose, *ref, u1, u2, G, tolerance)
        braked += v == (-3.0 * u1, -3.0 * u2)
        scale = out[ck.OUT_SCALE]
        _, _, base_vdot = planar_base(*pose, u1, u2, scale * v[0], scale * v[1])
        arm_acc = commanded_acceleration(position[arm_hw], velocity[arm_hw], *held, kp, kd, np.zeros(n))
        vdot = np.zeros(model.vdot.size)
        vdot[base : base + 6], vdot[arm_v - nq] = base_vdot, arm_acc
        (m, d, inertia, _), tau = drake_oracle(model, x, vdot, pose[2])
        K = constants(m, inertia, d, R, B, model.wheel_inertia, 1.0)
        tau_raw = feedback_linearization(*v, u1, u2, *K)
        tau_r, tau_l, s = saturate_pair(*tau_raw, limit)
        saturated += s < 1.0
        assert tuple(out[ck.OUT_V : ck.OUT_V + 2]) == v
        np.testing.assert_allclose(out[ck.OUT_K : ck.OUT_K + 4], K, rtol=1e-10)
        np.testing.assert_allclose(out[ck.OUT_TAU_RAW : ck.OUT_TAU_RAW + 2], tau_raw, rtol=1e-9)
        np.testing.assert_allclose([*out[ck.OUT_TAU : ck.OUT_TAU + 2], scale], [tau_r, tau_l, s], rtol=1e-9)
        np.testing.assert_allclose(model.vdot, vdot, rtol=1e-9, atol=1e-12)
        assert tuple(effort[wheels]) == tuple(out[ck.OUT_TAU : ck.OUT_TAU + 2])
        arm_tau = tau[arm_v - nq]
        np.testing.assert_allclose(effort[arm_hw], arm_tau, rtol=1e-9, atol=1e-9 * np.abs(tau).max())
    assert 10 < saturated < 110 and braked == 0  # both saturation branches, the law itself (not the brake)


def test_given_constants_replace_the_derived_ones(model):
    """With constants given (the lab's identified K5..K8, say), the mass matrix is not read."""
    n = 7
    given = (0.0844476, 3.770688, 2.646890, 16.084061)
    x, q_base, v_base, arm_q, arm_v = model.layout
    nq = model.plant.num_positions()
    params = ck.step_params(
        R,
        B,
        model.wheel_inertia,
        math.inf,
        0.003,
        0.1,
        CORRECTED,
        given,
        G,
        np.full(n, 25.0),
        np.full(n, 10.0),
    )
    index = ck.step_index(q_base, v_base, v_base - nq, [0, 1], arm_q, arm_v, np.arange(2, 9))
    out, inp = np.zeros(ck.out_size(n)), np.array([0, 0, 0, 1.0, 0.5, 0.2, 0.0, 1.0])
    velocity = np.array([1.0, 0.5, 0, 0, 0, 0, 0, 0, 0])
    ck.cart_step(
        inp,
        params,
        index,
        np.zeros(9),
        velocity,
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
        np.zeros(ck.ODO_SIZE),
        x,
        model.kernel.tree,
        model.kernel.extra,
        model.work,
        model.M,
        model.vdot,
        model.tau,
        out,
        np.zeros(9),
    )
    assert tuple(out[ck.OUT_K : ck.OUT_K + 4]) == given
    u = wheel_velocities_to_body(1.0, 0.5, R, B)
    v = command(CORRECTED, 0.0, 0.0, 0.0, 1.0, 0.5, 0.2, *u, G, 0.003)
    assert tuple(out[ck.OUT_TAU : ck.OUT_TAU + 2]) == feedback_linearization(*v, *u, *given)
