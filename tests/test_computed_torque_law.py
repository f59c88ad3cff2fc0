"""Computed-torque law (53) and its error dynamics (54)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from twil_control.control.computed_torque import computed_torque, gains_for, ideal_step_error

pytestmark = pytest.mark.kernels

N = 7  # WAM joints


def _random_spd(rng, n):
    a = rng.normal(size=(n, n))
    return a @ a.T + n * np.eye(n)


class _Plant:
    """M(q) q_ddot + c(q, q_dot) - tau_g(q) = tau, with configuration-dependent M, c, tau_g.

    M(q) = M0 + diag(0.5 + 0.4 sin q) is symmetric positive definite; c is quadratic in q_dot
    like Coriolis terms; tau_g = -G(q) as Drake's CalcGravityGeneralizedForces returns it.
    """

    def __init__(self, rng):
        self.m0 = _random_spd(rng, N)
        self.c0 = rng.normal(size=(N, N))
        self.g0 = rng.normal(size=N) * 10.0

    def mass(self, q):
        return self.m0 + np.diag(0.5 + 0.4 * np.sin(q))

    def bias(self, q, qd):
        return (self.c0 @ qd) * qd * np.cos(q)

    def tau_g(self, q):
        return -self.g0 * np.cos(q)

    def acceleration(self, q, qd, tau):
        return np.linalg.solve(self.mass(q), tau - self.bias(q, qd) + self.tau_g(q))


def _closed_loop(plant, reference, kp, kd):
    def rhs(t, x):
        q, qd = x[:N], x[N:]
        q_ref, qd_ref, qdd_ref = reference(t)
        tau = computed_torque(
            plant.mass(q), plant.bias(q, qd), plant.tau_g(q), q, qd, q_ref, qd_ref, qdd_ref, kp, kd
        )
        return np.r_[qd, plant.acceleration(q, qd, tau)]

    return rhs


def test_step_error_follows_critically_damped_closed_form_with_lab_gains():
    rng = np.random.default_rng(53)
    plant = _Plant(rng)
    kp, kd = 25.0, 10.0  # the lab's gains: wn = 5 rad/s, zeta = 1
    assert gains_for(5.0, 1.0) == (kp, kd)
    q_ref = rng.uniform(-1, 1, N)
    q0 = q_ref + rng.uniform(-0.5, 0.5, N)
    ts = np.linspace(0.0, 3.0, 61)
    sol = solve_ivp(
        _closed_loop(plant, lambda t: (q_ref, np.zeros(N), np.zeros(N)), kp, kd),
        (0.0, 3.0),
        np.r_[q0, np.zeros(N)],
        t_eval=ts,
        rtol=1e-11,
        atol=1e-13,
        method="DOP853",
    )
    error = q_ref[:, None] - sol.y[:N]
    expected = ideal_step_error(ts[None, :], (q_ref - q0)[:, None], wn=5.0)
    np.testing.assert_allclose(error, expected, atol=1e-9)
    np.testing.assert_allclose(
        expected[:, :1], (q_ref - q0)[:, None] * (1 + 5 * ts[:1]) * np.exp(-5 * ts[:1])
    )


def test_tracking_error_with_per_joint_gains_and_moving_reference():
    rng = np.random.default_rng(54)
    plant = _Plant(rng)
    wn = rng.uniform(2, 8, N)
    zeta = 0.7
    kp, kd = wn**2, 2 * zeta * wn
    amp, freq = rng.uniform(0.2, 1, N), rng.uniform(0.5, 2, N)

    def reference(t):
        return amp * np.sin(freq * t), amp * freq * np.cos(freq * t), -amp * freq**2 * np.sin(freq * t)

    e0, ed0 = rng.uniform(-0.3, 0.3, N), rng.uniform(-0.5, 0.5, N)
    q_ref0, qd_ref0, _ = reference(0.0)
    ts = np.linspace(0.0, 2.0, 41)
    sol = solve_ivp(
        _closed_loop(plant, reference, kp, kd),
        (0.0, 2.0),
        np.r_[q_ref0 - e0, qd_ref0 - ed0],
        t_eval=ts,
        rtol=1e-11,
        atol=1e-13,
        method="DOP853",
    )
    error = np.array([reference(t)[0] for t in ts]).T - sol.y[:N]
    for j in range(N):
        np.testing.assert_allclose(error[j], ideal_step_error(ts, e0[j], wn[j], zeta, ed0[j]), atol=1e-9)


def test_law_cancels_the_model_exactly():
    rng = np.random.default_rng(16)
    plant = _Plant(rng)
    for _ in range(20):
        q, qd, q_ref, qd_ref, qdd_ref = rng.normal(size=(5, N))
        tau = computed_torque(
            plant.mass(q), plant.bias(q, qd), plant.tau_g(q), q, qd, q_ref, qd_ref, qdd_ref, 25.0, 10.0
        )
        wanted = qdd_ref + 10.0 * (qd_ref - qd) + 25.0 * (q_ref - q)
        np.testing.assert_allclose(plant.acceleration(q, qd, tau), wanted, rtol=1e-10, atol=1e-10)


def test_closed_forms_solve_the_error_equation():
    # e_ddot + 2 zeta wn e_dot + wn^2 e = 0 with e(0) = e0, e_dot(0) = ed0, by finite differences.
    t, h = np.linspace(0.0, 2.0, 201), 1e-4
    for zeta in (0.3, 1.0, 1.0 + 1e-9, 2.5):
        e = lambda s: ideal_step_error(s, 0.8, 4.0, zeta, -0.3)  # noqa: E731
        residual = (
            (e(t + h) - 2 * e(t) + e(t - h)) / h**2
            + 2 * zeta * 4.0 * (e(t + h) - e(t - h)) / (2 * h)
            + 16.0 * e(t)
        )
        assert np.max(np.abs(residual)) < 1e-5
        assert e(0.0) == pytest.approx(0.8, abs=1e-12)
        assert (e(h) - e(-h)) / (2 * h) == pytest.approx(-0.3, abs=1e-6)


def test_mass_matrix_shape_is_checked():
    with pytest.raises(ValueError, match="M must be"):
        computed_torque(
            np.eye(3),
            np.zeros(2),
            np.zeros(2),
            np.zeros(2),
            np.zeros(2),
            np.zeros(2),
            np.zeros(2),
            np.zeros(2),
            1.0,
            1.0,
        )
