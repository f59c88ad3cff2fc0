"""control/cart_kernel.py (the cart controller's compiled update) against the pure-Python
reference it replaces in the 1 kHz loop: the corrected backstepping law and its brake, K5..K8
from the robot description, the feedback linearisation (9), the saturation of the wheel pair,
the base acceleration and the arm's law (53); the odometry against diff_odometry; and the whole
step (cart_step) against the same with Drake's mass matrix and inverse dynamics."""
from __future__ import annotations

import math

import numpy as np
import pytest

from twil_control.control import cart_kernel
from twil_control.control.angles import wrap_angle
from twil_control.control.backstepping import GAIN_NAMES, BacksteppingLaw
from twil_control.control.computed_torque import ComputedTorqueLaw
from twil_control.control.diff_odometry import WheelOdometry
from twil_control.control.platform_model import derive_constants, feedback_linearization, wheel_velocities_to_body
from twil_control.control.trajectory import second_order_hold
from twil_control.nodes.controllers.cart_linearizing import ARM_JOINTS, saturate_pair
from twil_control.world.platform_dynamics import PlatformMassModel, planar_base_state

GAINS = dict(gamma1=0.4, gamma2=1.0, gamma4=3.0, gamma5=3.0, lambda1=0.5, lambda2=1.0, lambda3=2.0,
             lambda4=1.0, lambda5=1.0)
G = np.array([GAINS[k] for k in GAIN_NAMES])
R, B = 0.075, 0.161
REL = 1e-12  # relative agreement (the same arithmetic, reordered in places)


def close(a, b, scale=1.0):
    return np.allclose(a, b, rtol=REL, atol=REL * scale)


@pytest.fixture(scope="module")
def model():
    return PlatformMassModel("twil_wam", ARM_JOINTS, ["right_wheel_joint", "left_wheel_joint"])


def random_cases(rng, n):
    """Poses, references and velocities: ordinary ones, near-goal ones (e from 1e-12 to 1e-2 m,
    around the tolerance), alpha near 0 (the sinc series), and overflowing ones."""
    for k in range(n):
        kind = k % 4
        pose = rng.uniform(-5, 5, 3)
        ref = rng.uniform(-5, 5, 3)
        u = rng.uniform(-1.5, 1.5, 2)
        if kind == 1:
            ref[:2] = pose[:2] + 10.0 ** rng.uniform(-12, -2) * rng.normal(size=2)
        elif kind == 2:  # heading along the bearing to the goal: alpha ~ 0
            bearing = math.atan2(pose[1] - ref[1], pose[0] - ref[0])
            pose[2] = bearing + 10.0 ** rng.uniform(-9, -1) * rng.choice([-1, 1])
        elif kind == 3 and k % 8 == 3:
            pose[:2] *= 1e306
            u *= 1e306
        yield pose, ref, u


def test_wrap_matches_the_reference_angle_wrap():
    angles = np.concatenate([np.linspace(-20, 20, 2001), [math.pi, -math.pi, 3 * math.pi, -3 * math.pi, 0.0]])
    for a in angles:
        assert cart_kernel.wrap(a) == wrap_angle(float(a))


def test_law_and_brake_match_backstepping_law_on_2000_states():
    rng = np.random.default_rng(7)
    tolerance = 0.003
    law = BacksteppingLaw(GAINS, law="corrected", goal_tolerance=tolerance)
    braked = 0
    for pose, ref, u in random_cases(rng, 2000):
        expected = law(tuple(pose), tuple(ref), tuple(u))
        got = cart_kernel.corrected_or_brake(*pose, *ref, *u, G, law.tolerance)
        assert close(got, expected, scale=max(1.0, np.abs(expected).max())), (pose, ref, u, got, expected)
        assert np.isfinite(got).all()
        braked += bool(np.allclose(expected, [-3.0 * u[0], -3.0 * u[1]]))
    assert 100 < braked < 1900  # both branches were exercised


def test_whole_update_matches_the_python_reference(model):
    rng = np.random.default_rng(11)
    x, q_base, v_base, arm_q, arm_v = model.layout
    nq = model.plant.num_positions()
    base, arm_vdot = v_base - nq, arm_v - nq
    joints = np.arange(7)
    kp, kd = np.full(7, 25.0), np.full(7, 10.0)
    arm_law = ComputedTorqueLaw(7, kp, kd)
    law = BacksteppingLaw(GAINS, goal_tolerance=0.003)
    out = np.zeros(cart_kernel.OUT_SIZE)
    saturated = 0
    for k in range(200):
        pose, ref, (u1, u2) = rng.uniform(-3, 3, 3), rng.uniform(-3, 3, 3), rng.uniform(-1, 1, 2)
        q, qd, q_r, qd_r, qdd_r = (rng.uniform(-1.5, 1.5, 7) for _ in range(5))
        limit = [math.inf, 6.0, 0.5][k % 3]
        cart_kernel.planar_state(x, q_base, v_base, arm_q, arm_v, pose[0], pose[1], pose[2], u1, u2, q, qd, joints)
        M = model.mass_matrix()
        vdot = model.vdot
        cart_kernel.cart_update(pose, ref, u1, u2, G, law.tolerance, x, M, base, arm_q, arm_v, R, B,
                                model.wheel_inertia, limit, q_r, qd_r, qdd_r, kp, kd, out, vdot)
        # the reference, step by step
        base_q, base_v, _ = planar_base_state(pose[0], pose[1], pose[2], u1, u2)
        model.set_state(base_q, base_v, q, qd)
        assert np.array_equal(model.layout[0], x)
        mp = model.planar_mass_properties(pose[2])
        K = derive_constants(mp.mass, mp.yaw_inertia, mp.d, R, B, wheel_inertia=model.wheel_inertia)
        v = law(tuple(pose), tuple(ref), (u1, u2))
        tau_raw = feedback_linearization(v, (u1, u2), K)
        tau, scale = saturate_pair(tau_raw, limit)
        saturated += scale < 1.0
        _, _, base_vdot = planar_base_state(pose[0], pose[1], pose[2], u1, u2, u1_dot=scale * v[0],
                                            u2_dot=scale * v[1])
        assert close(out[cart_kernel.OUT_V:cart_kernel.OUT_V + 2], v, scale=10.0)
        assert close(out[cart_kernel.OUT_K:cart_kernel.OUT_K + 4], [K.K5, K.K6, K.K7, K.K8], scale=10.0)
        assert close(out[cart_kernel.OUT_TAU_RAW:cart_kernel.OUT_TAU_RAW + 2], tau_raw, scale=100.0)
        assert close(out[cart_kernel.OUT_TAU:cart_kernel.OUT_TAU + 2], tau, scale=100.0)
        assert close(out[cart_kernel.OUT_SCALE], scale)
        assert close(vdot[base:base + 6], base_vdot, scale=10.0)
        assert close(vdot[arm_vdot], arm_law.acceleration(q, qd, q_r, qd_r, qdd_r), scale=100.0)
    assert 20 < saturated < 180  # saturated and unsaturated pairs both checked


def test_cart_step_equals_drake_and_the_tested_update(model):
    """The whole compiled update (cart_step: u, state, held arm reference, the compiled mass
    matrix and inverse dynamics, the law, the efforts) against the same steps with Drake's
    CalcMassMatrix and CalcInverseDynamics and the Python hold (trajectory.second_order_hold),
    for the odometry (planar, pose from odometry_step) and ground-truth (any base state) pose
    sources."""
    rng = np.random.default_rng(13)
    x, q_base, v_base, arm_q, arm_v = model.layout
    nq = model.plant.num_positions()
    base = v_base - nq
    hw_index = rng.permutation(9)  # where the hardware keeps each joint: right, left wheel, arm
    wheels, arm_hw = hw_index[:2], hw_index[2:]
    kp, kd = rng.uniform(5, 30, 7), rng.uniform(1, 10, 7)
    timeout, tolerance = 0.1, 0.003
    params = cart_kernel.step_params(R, B, model.wheel_inertia, 6.0, tolerance, timeout, G, kp, kd)
    index = cart_kernel.step_index(q_base, v_base, base, wheels, arm_q, arm_v, arm_hw)
    out = np.zeros(cart_kernel.step_out_size(7))
    out_ref = np.zeros(cart_kernel.OUT_SIZE)
    inp = np.zeros(cart_kernel.IN_SIZE)
    effort = np.zeros(9)
    for k in range(200):
        planar = k % 2 == 0
        position, velocity = rng.uniform(-2, 2, 9), rng.uniform(-2, 2, 9)
        pose, ref = rng.uniform(-3, 3, 3), rng.uniform(-3, 3, 3)
        q_s, qd_s, qdd_s = (rng.uniform(-1.5, 1.5, 7) for _ in range(3))
        age = [-0.01, 0.0, 0.03, 0.5][k % 4]
        inp[:] = [*pose, *ref, age, 1.0 if planar else 0.0]
        odometry = np.concatenate([rng.uniform(-3, 3, 3), position[wheels[::-1]] - rng.normal(0, 0.01, 2), [1.0]])
        if planar:  # the pose is the odometry's, one step on (odometry_step is tested below)
            expected = odometry.copy()
            cart_kernel.odometry_step(expected, position[wheels[1]], position[wheels[0]], R, 2 * B)
            pose = expected[:3]
        u1, u2 = wheel_velocities_to_body(velocity[wheels[0]], velocity[wheels[1]], R, B)
        if planar:
            base_q, base_v, _ = planar_base_state(pose[0], pose[1], pose[2], u1, u2)
        else:  # ground truth: the base's state as it is, tilted and moving in 3D
            quat = rng.normal(size=4)
            base_q, base_v = np.concatenate([quat / np.linalg.norm(quat), rng.uniform(-3, 3, 3)]), rng.normal(size=6)
            x[q_base:q_base + 7], x[v_base:v_base + 6] = base_q, base_v
        cart_kernel.cart_step(inp, params, index, position, velocity, q_s, qd_s, qdd_s, odometry, x,
                              model.kernel.tree, model.kernel.extra, model.work, model.M, model.vdot, model.tau, out,
                              effort)
        assert np.array_equal(inp[:3], pose)
        vdot, tau = model.vdot.copy(), model.tau.copy()
        # the reference: Drake's dynamics and the Python hold around the tested cart_update
        x_got = x.copy()
        model.set_state(base_q, base_v, position[arm_hw], velocity[arm_hw])
        assert np.allclose(x_got, model.layout[0], rtol=1e-15, atol=1e-15)
        dt = min(max(age, 0.0), timeout)
        q_r, qd_r = second_order_hold(q_s, qd_s, qdd_s, dt)
        qdd_r = qdd_s
        if age > timeout:
            qd_r, qdd_r = np.zeros(7), np.zeros(7)
        M = model.mass_matrix()
        vdot_ref = model.vdot
        cart_kernel.cart_update(pose, ref, u1, u2, G, tolerance, x, M, base, arm_q, arm_v, R, B,
                                model.wheel_inertia, 6.0, q_r, qd_r, qdd_r, kp, kd, out_ref, vdot_ref)
        tau_ref = model.inverse_dynamics()
        rel = 1e-10  # Drake's M and the kernel's differ in the last digits (~1e-14 relative)
        assert np.allclose(out[:cart_kernel.OUT_SIZE], out_ref, rtol=rel, atol=rel * 100)
        assert np.allclose(out[cart_kernel.OUT_U:cart_kernel.OUT_U + 2], [u1, u2], rtol=1e-15, atol=0)
        assert np.allclose(out[cart_kernel.OUT_REF:], np.concatenate([q_r, qd_r, qdd_r]), rtol=1e-15, atol=1e-15)
        assert np.allclose(vdot, vdot_ref, rtol=rel, atol=rel * 100)
        assert np.allclose(tau, tau_ref, rtol=rel, atol=rel * np.abs(tau_ref).max())
        assert np.array_equal(effort[wheels], out[cart_kernel.OUT_TAU:cart_kernel.OUT_TAU + 2])
        assert np.array_equal(effort[arm_hw], tau[arm_v - nq])


def test_odometry_step_follows_wheel_odometry():
    """odometry_step against diff_odometry.WheelOdometry (the reference) over 3,000 updates of
    random wheel increments: straight runs (the RK2 branch, |dtheta| < 1e-6), turns on the spot
    and arcs (the exact branch); the first call only records the angles, as in WheelOdometry."""
    rng = np.random.default_rng(17)
    reference = WheelOdometry(R, 2 * B)
    odometry = np.zeros(cart_kernel.ODO_SIZE)
    left, right = rng.uniform(-10, 10, 2)
    for k in range(3000):
        reference.update(left, right, k * 1e-3)
        cart_kernel.odometry_step(odometry, left, right, R, 2 * B)
        expected = reference.pose
        assert np.allclose(odometry[:3], expected, rtol=1e-12, atol=1e-12), (k, odometry[:3], expected)
        step = rng.uniform(-0.05, 0.05)
        kind = k % 3
        d_left, d_right = (step, step + rng.uniform(-1e-6, 1e-6) * B / R) if kind == 0 else \
            (step, -step) if kind == 1 else rng.uniform(-0.05, 0.05, 2)
        left, right = left + d_left, right + d_right
    assert reference.pose[0] != 0.0 and abs(reference.pose[2]) > 0.1  # it moved and turned
