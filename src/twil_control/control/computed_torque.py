"""Computed-torque control of the WAM, eqs. (16), (53)-(54).

The law (53), tau = D(q) [q_r_ddot + Kd (q_r_dot - q_dot) + Kp (q_r - q)] + H + G, cancels the
model (16), so the error follows e_ddot + Kd e_dot + Kp e = 0 (54). The arguments take Drake's
outputs as they come: M = CalcMassMatrix (D), c = CalcBiasTerm (H) and
tau_g = CalcGravityGeneralizedForces (-G), so the law is tau = M a + c - tau_g.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from twil_control.errors import InputError

__all__ = [
    "ComputedTorqueLaw",
    "computed_torque",
    "commanded_acceleration",
    "joint_gains",
    "gains_for",
    "ideal_step_error",
]


def joint_gains(k, n: int, name: str) -> np.ndarray:
    """A gain for each of n joints from one number (the lab's Kp = 25 on every joint) or a list
    of n; ValueError naming `name` unless every gain is finite and non-negative."""
    try:
        arr = np.asarray(k, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number or a list of {n} numbers (got {k!r})") from None
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,) or not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise InputError(f"{name} must be finite and non-negative: one number or a list of {n} (got {k!r})")
    return arr


@njit(cache=True, nogil=True)
def commanded_acceleration(q, qd, q_ref, qd_ref, qdd_ref, kp, kd, out):
    """a = q_r_ddot + Kd (q_r_dot - q_dot) + Kp (q_r - q), the bracket of (53), into `out` (and
    returned). kp, kd: per-joint gains (diagonal Kp, Kd; `joint_gains` makes them). With an
    inverse-dynamics model, law (53) is tau = ID(q, q_dot, a)."""
    for k in range(out.shape[0]):
        out[k] = qdd_ref[k] + kd[k] * (qd_ref[k] - qd[k]) + kp[k] * (q_ref[k] - q[k])
    return out


def computed_torque(M, c, tau_g, q, qd, q_ref, qd_ref, qdd_ref, kp, kd) -> np.ndarray:
    """tau = M [q_r_ddot + Kd (q_r_dot - q_dot) + Kp (q_r - q)] + c - tau_g, eq. (53).

    M: mass matrix D(q) (n x n); c: Coriolis and centrifugal forces C(q, q_dot) q_dot = H of (16);
    tau_g: gravity generalised forces as Drake returns them, tau_g = -G(q). kp, kd: one gain for
    every joint (the lab's Kp = 25, Kd = 10) or one per joint.
    """
    q, qd, q_ref, qd_ref, qdd_ref = (np.asarray(v, dtype=float) for v in (q, qd, q_ref, qd_ref, qdd_ref))
    n = q.shape[0]
    gains = joint_gains(kp, n, "kp"), joint_gains(kd, n, "kd")
    a = commanded_acceleration(q, qd, q_ref, qd_ref, qdd_ref, *gains, np.empty(n))
    M = np.asarray(M, dtype=float)
    if M.shape != (n, n):
        raise InputError(f"M must be {n}x{n}, got shape {M.shape}")
    return M @ a + np.asarray(c, dtype=float) - np.asarray(tau_g, dtype=float)


def gains_for(wn: float, zeta: float = 1.0) -> tuple[float, float]:
    """(Kp, Kd) = (wn^2, 2 zeta wn) that give (54) the natural frequency wn and damping zeta.

    The lab's Kp = 25, Kd = 10 are wn = 5 rad/s, zeta = 1.
    """
    return wn * wn, 2.0 * zeta * wn


def ideal_step_error(t, e0, wn: float, zeta: float = 1.0, ed0=0.0):
    """Closed-form solution of (54), e_ddot + 2 zeta wn e_dot + wn^2 e = 0, e(0) = e0, e_dot(0) = ed0.

    zeta = 1 (critical, the lab's gains): e = (e0 + (ed0 + wn e0) t) exp(-wn t), which for a
    step (ed0 = 0) is e0 (1 + wn t) exp(-wn t). zeta < 1 and zeta > 1 use the under- and
    over-damped forms. t, e0 and ed0 broadcast (e0 may be a vector of joint errors).
    """
    if not (wn > 0.0 and zeta >= 0.0):
        raise InputError(f"need wn > 0 and zeta >= 0, got wn={wn}, zeta={zeta}")
    t = np.asarray(t, dtype=float)
    e0 = np.asarray(e0, dtype=float)
    ed0 = np.asarray(ed0, dtype=float)
    if zeta == 1.0:
        return (e0 + (ed0 + wn * e0) * t) * np.exp(-wn * t)
    if zeta < 1.0:
        wd = wn * math.sqrt(1.0 - zeta * zeta)
        return np.exp(-zeta * wn * t) * (e0 * np.cos(wd * t) + (ed0 + zeta * wn * e0) / wd * np.sin(wd * t))
    # Over-damped: e = exp(-zeta wn t) (e0 cosh(s t) + (ed0 + zeta wn e0) sinh(s t)/s). The
    # hyperbolic form avoids the cancellation of the two exponentials when zeta is near 1; for
    # s t >= 1 the exponential form avoids overflow of cosh and sinh at large t.
    s = wn * math.sqrt(zeta * zeta - 1.0)
    r1, r2 = -zeta * wn + s, -zeta * wn - s
    st = s * t
    small = st < 1.0
    st_small = np.where(small, st, 0.0)
    decay = np.exp(-zeta * wn * t)
    cosh_term = np.where(small, decay * np.cosh(st_small), 0.5 * (np.exp(r1 * t) + np.exp(r2 * t)))
    sinh_term = np.where(small, decay * np.sinh(st_small) / s, (np.exp(r1 * t) - np.exp(r2 * t)) / (2.0 * s))
    return e0 * cosh_term + (ed0 + zeta * wn * e0) * sinh_term


class ComputedTorqueLaw:
    """The bracket of law (53) for a fixed joint count and fixed gains, checked once, for a
    1 kHz loop: `acceleration` is `commanded_acceleration` into a reused buffer (copy it to keep
    it), to be fed to an inverse-dynamics model (tau = M a + c - tau_g)."""

    def __init__(self, n: int, kp, kd) -> None:
        self.n = n
        self.kp = joint_gains(kp, n, "kp")
        self.kd = joint_gains(kd, n, "kd")
        self._a = np.zeros(n)

    def acceleration(self, q, qd, q_ref, qd_ref, qdd_ref) -> np.ndarray:
        return commanded_acceleration(q, qd, q_ref, qd_ref, qdd_ref, self.kp, self.kd, self._a)
