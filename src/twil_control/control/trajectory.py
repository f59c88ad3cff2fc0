"""Smooth joint trajectories for references: the quintic rest-to-rest segment.

A step reference makes computed torque's error follow (54) from e0 and, for a large step, asks
for torques beyond the motors' limits (the WAM's joint 2 saturates going from straight up to
home). A trajectory with continuous position, velocity and acceleration, sent with its
velocity and acceleration, is what law (53) is written for: its error then stays at zero
whenever the model is right.
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["quintic", "held_reference"]


def quintic(q0, q1, duration: float, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, qd, qdd) at time t of the minimum-jerk segment from q0 to q1 over `duration`, at
    rest at both ends: s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5, tau = t / duration, clamped to
    [0, 1] (before the start: q0 at rest; after the end: q1 at rest)."""
    q0 = np.asarray(q0, dtype=float)
    dq = np.asarray(q1, dtype=float) - q0
    if not duration > 0.0:
        raise ValueError(f"duration must be > 0 s (got {duration!r})")
    tau = min(max(t / duration, 0.0), 1.0)
    s = tau ** 3 * (10.0 + tau * (-15.0 + 6.0 * tau))
    sd = 30.0 * tau ** 2 * (1.0 - tau) ** 2 / duration
    sdd = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / duration ** 2
    return q0 + s * dq, sd * dq, sdd * dq


@njit(cache=True, nogil=True)
def held_reference(q, qd, qdd, age, timeout):
    """(q_r, qd_r, qdd_r) `age` seconds after a sample (q, qd, qdd) of a trajectory, held to second
    order, exact for constant acceleration (error jerk dt^3 / 6): q_r = q + qd dt + qdd dt^2 / 2,
    qd_r = qd + qdd dt, qdd_r = qdd, with dt = age clamped to [0, timeout]; after `timeout` the
    sample's publisher is taken as silent and the reference holds still at the position
    reached (qd_r = qdd_r = 0). Floats or arrays (broadcast)."""
    dt = np.minimum(np.maximum(age, 0.0), timeout)
    moving = 1.0 * (age <= timeout)
    return q + dt * (qd + 0.5 * dt * qdd), (qd + dt * qdd) * moving, qdd * moving
