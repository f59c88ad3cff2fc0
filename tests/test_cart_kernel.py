"""control/cart_kernel.py (the cart controller's compiled update) against the pure-Python
reference it replaces in the 1 kHz loop: the corrected backstepping law and its brake, K5..K8
from the robot description, the feedback linearisation (9), the saturation of the wheel pair,
the base acceleration and the arm's law (53)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from twil_control.control import cart_kernel
from twil_control.control.angles import wrap_angle
from twil_control.control.backstepping import GAIN_NAMES, BacksteppingLaw
from twil_control.control.computed_torque import ComputedTorqueLaw
from twil_control.control.platform_model import derive_constants, feedback_linearization
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
