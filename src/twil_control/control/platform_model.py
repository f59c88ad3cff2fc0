"""Dynamic model of the TWIL differential-drive platform, eqs. (8)-(15), and its linearisation (9).

u_dot = -f(u) + F tau with -f(u) = [K5 u2^2, K6 u1 u2] (14) and F = [[K7, K7], [K8, -K8]] (15);
u = (u1, u2) = (v, w); tau = [tau_right, tau_left], positive driving forward, so K8 > 0. The
paper's form (14) is kept exactly: Newton-Euler gives K5 and K6 opposite signs, which the lab's
identified constants (`IDENTIFIED`) do not have (docs/errata.md, "Platform constants K5..K8");
`derive_constants` gives a model that matches the simulated plant. The equations are compiled
functions of floats (numba), called from Python and composed by the cart controller's update.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from twil_control.errors import InputError

__all__ = [
    "PlatformConstants",
    "IDENTIFIED",
    "constants",
    "derive_constants",
    "planar_mass_properties",
    "f_vector",
    "input_matrix",
    "dynamics",
    "feedback_linearization",
    "saturate_pair",
    "wheel_velocities_to_body",
    "body_to_wheel_velocities",
]


@dataclass(frozen=True)
class PlatformConstants:
    """K5..K8 of (14)-(15); docs/errata.md says what their signs mean."""

    K5: float
    K6: float
    K7: float
    K8: float

    def __post_init__(self) -> None:
        for name in ("K5", "K6", "K7", "K8"):
            if not math.isfinite(getattr(self, name)):
                raise InputError(f"{name} must be finite, got {getattr(self, name)}")
        if self.K7 == 0.0 or self.K8 == 0.0:
            raise InputError(
                f"K7 and K8 must be non-zero (F of (15) singular), got K7={self.K7}, K8={self.K8}"
            )

    def values(self) -> tuple[float, float, float, float]:
        return self.K5, self.K6, self.K7, self.K8


# Identified by the lab (its TWIL controller configuration). Same-sign K5, K6: docs/errata.md.
IDENTIFIED = PlatformConstants(K5=0.0844476, K6=3.770688, K7=2.646890, K8=16.084061)


@njit(cache=True, nogil=True)
def constants(m, yaw_inertia, d, r, b, wheel_inertia, sign):
    """(K5, K6, K7, K8) of (14)-(15) by Newton-Euler (docs/errata.md): K5 = m d/m_eff,
    K6 = -m d/I_eff, K7 = 1/(r m_eff), K8 = sign b/(r I_eff), with m_eff = m + 2 Iw/r^2 and
    I_eff = I + m d^2 + 2 Iw b^2/r^2; sign +1 for the (right, left) torque order, -1 for
    (left, right). Arguments as `derive_constants`, unchecked."""
    m_eff = m + 2.0 * wheel_inertia / (r * r)
    i_eff = yaw_inertia + m * d * d + 2.0 * wheel_inertia * b * b / (r * r)
    return m * d / m_eff, -m * d / i_eff, 1.0 / (r * m_eff), sign * b / (r * i_eff)


def derive_constants(
    mass: float,
    yaw_inertia: float,
    com_offset_d: float,
    wheel_radius: float,
    half_axle_b: float,
    *,
    wheel_inertia: float = 0.0,
    torque_order: tuple[str, str] = ("right", "left"),
) -> PlatformConstants:
    """K5..K8 of (14)-(15) from mass properties, by Newton-Euler (`constants`, docs/errata.md).

    mass: total mass m of the platform including its wheels (kg).
    yaw_inertia: I, yaw inertia of the whole platform, wheels included as point/rigid masses,
        about the vertical axis through the centre of mass (kg m^2).
    com_offset_d: d, distance of the centre of mass ahead of the axle midpoint (m, < 0 behind).
    wheel_radius: r (m); half_axle_b: b, half the distance between the wheels (m).
    wheel_inertia: Iw, spin inertia of ONE driven wheel about its axle, rotor inertia reflected
        through the gear included (kg m^2). Each wheel's spin is phi_dot = (v +- b w)/r, and
        Iw phi_ddot = tau - r F_ground, so the spin inertias add 2 Iw/r^2 (Iw/r^2 per wheel) to
        the mass in the v equation and 2 Iw b^2/r^2 to the inertia in the w equation; the
        wheels' translational mass is already in `mass` and `yaw_inertia`.
    torque_order: the order of the two torques in tau. ("right", "left") gives K8 > 0;
        ("left", "right") gives K8 < 0 so that F = [[K7, K7], [K8, -K8]] keeps its form.
    """
    values = dict(mass=mass, yaw_inertia=yaw_inertia, wheel_radius=wheel_radius, half_axle_b=half_axle_b)
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0.0):
            raise InputError(f"{name} must be finite and > 0, got {value}")
    if not math.isfinite(com_offset_d):
        raise InputError(f"com_offset_d must be finite, got {com_offset_d}")
    if not (math.isfinite(wheel_inertia) and wheel_inertia >= 0.0):
        raise InputError(f"wheel_inertia must be finite and >= 0, got {wheel_inertia}")
    orders = {("right", "left"): 1.0, ("left", "right"): -1.0}
    if tuple(torque_order) not in orders:
        raise InputError(f"torque_order must be one of {list(orders)}, got {torque_order!r}")
    return PlatformConstants(
        *constants(
            float(mass),
            float(yaw_inertia),
            float(com_offset_d),
            float(wheel_radius),
            float(half_axle_b),
            float(wheel_inertia),
            orders[(torque_order[0], torque_order[1])],
        )
    )


@njit(cache=True, nogil=True)
def planar_mass_properties(M, base, yaw):
    """(m, d, I, lateral) of the whole robot from its mass matrix M, whose base block (rows and
    columns base..base+5, angular then translational: a free body's velocities in Drake) is the
    robot's spatial inertia about base_link's origin in world axes: M[trans, trans] = m 1 and
    M[ang, trans] = m [p]x with p the centre of mass from base_link's origin. `yaw` turns p into
    base_link's axes: d ahead of the axle midpoint, lateral to the left; I = M[yaw, yaw] -
    m (p_x^2 + p_y^2), the yaw inertia about the centre of mass (parallel axes; the floor is
    flat, base_link upright)."""
    i, j = base, base + 3
    m = M[j, j]
    px, py = M[i + 2, j + 1] / m, M[i, j + 2] / m
    c, s = math.cos(yaw), math.sin(yaw)
    return m, c * px + s * py, M[i + 2, i + 2] - m * (px * px + py * py), -s * px + c * py


@njit(cache=True, nogil=True)
def f_vector(u1, u2, K5, K6):
    """f(u) = -[[0, K5], [K6, 0]] [u1 u2, u2^2]^T = -(K5 u2^2, K6 u1 u2), eq. (14)."""
    return -K5 * u2 * u2, -K6 * u1 * u2


def input_matrix(K: PlatformConstants) -> np.ndarray:
    """F = [[K7, K7], [K8, -K8]], eq. (15); det F = -2 K7 K8 != 0."""
    return np.array([[K.K7, K.K7], [K.K8, -K.K8]])


@njit(cache=True, nogil=True)
def dynamics(u1, u2, tau_r, tau_l, K5, K6, K7, K8):
    """u_dot = -f(u) + F tau, eq. (8) with H = I (13) and (14)-(15), tau = (tau_right, tau_left)."""
    f1, f2 = f_vector(u1, u2, K5, K6)
    return -f1 + K7 * (tau_r + tau_l), -f2 + K8 * (tau_r - tau_l)


@njit(cache=True, nogil=True)
def feedback_linearization(v1, v2, u1, u2, K5, K6, K7, K8):
    """(tau_right, tau_left) = F^-1 (H v + f(u)) with H = I, eq. (9): makes the dynamics (8)
    read u_dot = v (10). F is square and invertible, so F-dagger is its inverse, written out:
    tau_right = (v1 + f1)/(2 K7) + (v2 + f2)/(2 K8), tau_left = (v1 + f1)/(2 K7) - (v2 + f2)/(2 K8)."""
    f1, f2 = f_vector(u1, u2, K5, K6)
    a = (v1 + f1) / (2.0 * K7)
    c = (v2 + f2) / (2.0 * K8)
    return a + c, a - c


@njit(cache=True, nogil=True)
def saturate_pair(tau_r, tau_l, limit):
    """(tau_r, tau_l, s): the wheel pair scaled by one factor s <= 1 so that max |tau| <= limit.
    Clipping each wheel on its own would change tau_r/tau_l and so turn a forward command into
    a turn; one factor keeps the direction of F tau (the acceleration u_dot = s v)."""
    peak = max(abs(tau_r), abs(tau_l))
    if peak <= limit:
        return tau_r, tau_l, 1.0
    s = limit / peak
    return tau_r * s, tau_l * s, s


@njit(cache=True, nogil=True)
def wheel_velocities_to_body(wr, wl, r, b):
    """(u1, u2) from wheel rates (rad/s): u1 = r (wr + wl)/2, u2 = r (wr - wl)/(2 b). Kinematics (11)-(12)."""
    return r * (wr + wl) / 2.0, r * (wr - wl) / (2.0 * b)


@njit(cache=True, nogil=True)
def body_to_wheel_velocities(u1, u2, r, b):
    """(wr, wl) wheel rates (rad/s) for body velocity (u1, u2): wr = (u1 + b u2)/r, wl = (u1 - b u2)/r."""
    return (u1 + b * u2) / r, (u1 - b * u2) / r
