"""Error coordinates of the platform: offset to origin (18)-(19), polar coordinates (20)-(22).

Poses are (x, y, theta) of the axle midpoint in the world frame. The reference pose becomes the
origin of a new frame, and (e, psi, alpha) are the pose's polar coordinates there: the distance,
the bearing of the platform seen from the reference, the heading relative to that bearing, with
angles in (-pi, pi]. Compiled functions of floats (numba), composed by the cart controller's
update too; `as_pose` checks a pose at the Python boundary.
"""

from __future__ import annotations

import math

from numba import njit

from twil_control.control.angles import wrap_angle
from twil_control.errors import InputError

__all__ = ["as_pose", "offset_to_origin", "polar_coordinates", "error_coordinates", "polar_kinematics"]


def as_pose(pose, name: str = "pose") -> tuple[float, float, float]:
    """(x, y, theta) as floats; ValueError naming `name` if not 3 finite numbers."""
    try:
        x, y, th = pose
    except (TypeError, ValueError) as err:
        raise InputError(f"{name} must be (x, y, theta), got {pose!r}") from err
    x, y, th = float(x), float(y), float(th)
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(th)):
        raise InputError(f"{name} must be finite, got {(x, y, th)}")
    return x, y, th


@njit(cache=True, nogil=True)
def offset_to_origin(x, y, th, xr, yr, thr):
    """x_bar = [[R(x_r3), 0], [0, 1]] (x - x_r), eq. (18), with R of eq. (19).

    R(a) = [[cos a, sin a], [-sin a, cos a]] rotates the world-frame offset into the reference
    frame. x_bar3 = theta - theta_r is wrapped to (-pi, pi]. Returns (x_bar1, x_bar2, x_bar3).
    """
    c, s = math.cos(thr), math.sin(thr)
    dx, dy = x - xr, y - yr
    return c * dx + s * dy, -s * dx + c * dy, wrap_angle(th - thr)


@njit(cache=True, nogil=True)
def polar_coordinates(xb1, xb2, xb3):
    """(e, psi, alpha) from x_bar, eqs. (20)-(22).

    e = sqrt(x_bar1^2 + x_bar2^2) (20), psi = atan2(x_bar2, x_bar1) (21),
    alpha = x_bar3 - psi (22), both angles wrapped to (-pi, pi]. At e = 0 psi is undefined;
    atan2(0, 0) = 0 is returned (the control law treats e below its goal tolerance separately).
    """
    e = math.hypot(xb1, xb2)
    psi = math.atan2(xb2, xb1)
    if psi == -math.pi:  # atan2(-0.0, x < 0); (-pi, pi] wants +pi
        psi = math.pi
    return e, psi, wrap_angle(xb3 - psi)


@njit(cache=True, nogil=True)
def error_coordinates(x, y, th, xr, yr, thr):
    """(e, psi, alpha) of the pose (x, y, th) relative to (xr, yr, thr): (18)-(19), then (20)-(22)."""
    xb1, xb2, xb3 = offset_to_origin(x, y, th, xr, yr, thr)
    return polar_coordinates(xb1, xb2, xb3)


@njit(cache=True, nogil=True)
def polar_kinematics(e, alpha, u1, u2):
    """(e_dot, psi_dot, alpha_dot) of the platform for velocity u = (u1, u2), eqs. (30)-(32).

    e_dot = cos(alpha) u1, psi_dot = sin(alpha)/e u1, alpha_dot = -sin(alpha)/e u1 + u2.
    Singular at e = 0 (psi and alpha are undefined there); the caller keeps e > 0.
    """
    s_e = math.sin(alpha) / e
    return math.cos(alpha) * u1, s_e * u1, -s_e * u1 + u2
