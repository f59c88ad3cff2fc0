"""How the bag analysis measures the deviation from (54), e'' + Kd e' + Kp e = 0, on signals whose
answer is known: an ideal closed loop (0), a plant that delivers 90% of the commanded
acceleration (10%), a constant error (Kp e exactly); and how it finds clipped efforts."""

from __future__ import annotations

import numpy as np
import pytest

from twil_control.bag.analyses import computed_torque_tracking as computed_torque
from twil_control.bag.analyses.step_response import error_dynamics_residual
from twil_control.control.trajectory import quintic

pytestmark = pytest.mark.kernels

KP, KD, H, TIMEOUT = 25.0, 10.0, 0.01, 0.1


def reference_samples(t_end=4.0):
    """A two-joint quintic from 0 to (1, -0.5) over 3 s from t = 0.5, sampled at 100 Hz."""
    cmd_t = np.arange(0.5, t_end, H)
    samples = [quintic([0.0, 0.0], [1.0, -0.5], 3.0, t - 0.5) for t in cmd_t]
    return cmd_t, *(np.array([s[i] for s in samples]) for i in range(3))


def closed_loop(gain: float, e0=(0.02, -0.01), substeps=4):
    """Joint states at 100 Hz of a plant whose acceleration is `gain` times the acceleration law
    (53) commands, the reference held as the controller holds it (RK4, H / substeps)."""
    cmd_t, q_s, qd_s, qdd_s = reference_samples()
    q = -np.asarray(e0, float)  # the reference starts at 0: e(0.5) = e0
    qd = np.zeros(2)
    ts, qs, qds = [cmd_t[0]], [q.copy()], [qd.copy()]
    for k, t0 in enumerate(cmd_t[:-1]):

        def accel(t, q, qd):  # the controller's hold of sample k (second order, within the timeout)
            dt = t - t0
            q_r, qd_r = q_s[k] + dt * (qd_s[k] + 0.5 * dt * qdd_s[k]), qd_s[k] + dt * qdd_s[k]
            return gain * (qdd_s[k] + KD * (qd_r - qd) + KP * (q_r - q))

        dt = H / substeps
        for i in range(substeps):
            t = t0 + i * dt
            k1q, k1v = qd, accel(t, q, qd)
            k2q, k2v = qd + 0.5 * dt * k1v, accel(t + dt / 2, q + 0.5 * dt * k1q, qd + 0.5 * dt * k1v)
            k3q, k3v = qd + 0.5 * dt * k2v, accel(t + dt / 2, q + 0.5 * dt * k2q, qd + 0.5 * dt * k2v)
            k4q, k4v = qd + dt * k3v, accel(t + dt, q + dt * k3q, qd + dt * k3v)
            q = q + dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
            qd = qd + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        ts.append(cmd_t[k + 1])
        qs.append(q.copy())
        qds.append(qd.copy())
    return np.array(ts), np.array(qs), np.array(qds), (cmd_t, q_s, qd_s, qdd_s)


def test_an_ideal_closed_loop_deviates_by_nothing():
    t, q, qd, cmds = closed_loop(1.0)
    r = error_dynamics_residual(t, q, qd, *cmds, KP, KD, TIMEOUT)
    assert r["residual"].shape == (len(t) - 1, 2)
    assert (r["percent"] < 0.01).all(), r["percent"]  # measured 0.003%: the trapezoid of Kp e over 10 ms


def test_a_plant_delivering_90_percent_of_the_acceleration_deviates_by_10_percent():
    t, q, qd, cmds = closed_loop(0.9)
    r = error_dynamics_residual(t, q, qd, *cmds, KP, KD, TIMEOUT)
    np.testing.assert_allclose(r["percent"], 10.0, atol=0.05)
    # the residual is the commanded acceleration the joint did not get: a - qdd = 0.1 a
    np.testing.assert_allclose(r["residual"], 0.1 * r["commanded"], atol=1e-3 * np.abs(r["commanded"]).max())


def test_a_constant_error_leaves_kp_e_exactly():
    """A constant-acceleration reference (held exactly between samples) and a joint following it
    a constant offset behind: e' = e'' = 0, so the residual is Kp e."""
    t = np.arange(0.5, 2.0, H)
    c = np.array([0.4, -0.3])
    q_s, qd_s, qdd_s = 0.5 * c * t[:, None] ** 2, c * t[:, None], np.tile(c, (len(t), 1))
    offset = np.array([0.01, -0.02])
    r = error_dynamics_residual(t, q_s - offset, qd_s, t, q_s, qd_s, qdd_s, KP, KD, TIMEOUT)
    np.testing.assert_allclose(r["residual"], np.tile(KP * offset, (len(t) - 1, 1)), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(r["commanded"], np.tile(c + KP * offset, (len(t) - 1, 1)), rtol=1e-9)


def test_a_step_between_samples_opens_the_next_interval():
    """A step at a joint-state time: the interval before it still holds the old reference."""
    t = np.arange(0.0, 1.0, H)
    q = np.zeros((len(t), 1))
    r = error_dynamics_residual(
        t, q, np.zeros_like(q), [0.0, 0.5], [[0.0], [0.2]], [[0.0], [0.0]], [[0.0], [0.0]], KP, KD, TIMEOUT
    )
    before = r["t"] < 0.5
    assert not r["residual"][before].any()
    np.testing.assert_allclose(r["residual"][~before], KP * 0.2)


def test_clipped_intervals_and_the_description_limits():
    flags = np.array([0, 1, 1, 0, 0, 1, 0], bool)
    t = np.arange(7) * 0.01
    assert computed_torque._intervals(t, flags, 0.01) == [
        (0.01, pytest.approx(0.03)),
        (0.05, pytest.approx(0.06)),
    ]
    limits = computed_torque.description_effort_limits(
        tuple(f"wam_joint_{i}" for i in range(1, 8)) + ("nope",)
    )
    assert limits == {
        "wam_joint_1": 75.6,
        "wam_joint_2": 50.85,
        "wam_joint_3": 50.85,
        "wam_joint_4": 28.8,
        "wam_joint_5": 5.688,
        "wam_joint_6": 5.688,
        "wam_joint_7": 9.152,
    }
