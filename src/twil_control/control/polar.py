"""Error coordinates of the platform: offset to origin (18)-(19), polar coordinates (20)-(22).

Poses are (x, y, theta) of the axle midpoint in the world frame (the point whose velocity is
u1 along the heading, kinematics (11)-(12)). The reference pose x_r becomes the origin of a new
frame, x_bar is the pose in that frame, and (e, psi, alpha) are its polar coordinates: e the
distance to the reference, psi the bearing of the platform seen from the reference frame, alpha
the heading relative to that bearing. Angles are wrapped to (-pi, pi].
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from twil_control.control.angles import wrap_angle

__all__ = [
    "PolarError",
    "as_pose",
    "offset_to_origin",
    "polar_coordinates",
    "error_coordinates",
    "error_coordinates_unchecked",
    "polar_kinematics",
]


class PolarError(NamedTuple):
    """(e, psi, alpha) of (20)-(22)."""

    e: float
    psi: float
    alpha: float


def as_pose(pose, name: str = "pose") -> tuple[float, float, float]:
    """(x, y, theta) as floats; ValueError naming `name` if not 3 finite numbers."""
    try:
        x, y, th = pose
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name} must be (x, y, theta), got {pose!r}") from err
    x, y, th = float(x), float(y), float(th)
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(th)):
        raise ValueError(f"{name} must be finite, got {(x, y, th)}")
    return x, y, th


def offset_to_origin(pose, pose_ref) -> np.ndarray:
    """x_bar = [[R(x_r3), 0], [0, 1]] (x - x_r), eq. (18), with R of eq. (19).

    R(a) = [[cos a, sin a], [-sin a, cos a]] rotates the world-frame offset into the reference
    frame. x_bar3 = theta - theta_r is wrapped to (-pi, pi]. Returns an array of shape (3,).
    """
    return np.array(_offset_to_origin(as_pose(pose, "pose"), as_pose(pose_ref, "pose_ref")))


def _offset_to_origin(pose, pose_ref) -> tuple[float, float, float]:
    # (18)-(19) on validated float triples.
    x, y, th = pose
    xr, yr, thr = pose_ref
    c, s = math.cos(thr), math.sin(thr)
    dx, dy = x - xr, y - yr
    return c * dx + s * dy, -s * dx + c * dy, wrap_angle(th - thr)


def polar_coordinates(x_bar) -> PolarError:
    """(e, psi, alpha) from x_bar, eqs. (20)-(22).

    e = sqrt(x_bar1^2 + x_bar2^2) (20), psi = atan2(x_bar2, x_bar1) (21),
    alpha = x_bar3 - psi (22), both angles wrapped to (-pi, pi]. At e = 0 psi is undefined;
    atan2(0, 0) = 0 is returned (the control law treats e below its goal tolerance separately).
    """
    xb1, xb2, xb3 = (float(v) for v in x_bar)
    return _polar_coordinates(xb1, xb2, xb3)


def _polar_coordinates(xb1: float, xb2: float, xb3: float) -> PolarError:
    e = math.hypot(xb1, xb2)
    psi = math.atan2(xb2, xb1)
    if psi == -math.pi:  # atan2(-0.0, x < 0); (-pi, pi] wants +pi
        psi = math.pi
    return PolarError(e, psi, wrap_angle(xb3 - psi))


def error_coordinates(pose, pose_ref) -> PolarError:
    """(e, psi, alpha) of pose relative to pose_ref: (18)-(19) followed by (20)-(22)."""
    return _polar_coordinates(*_offset_to_origin(as_pose(pose, "pose"), as_pose(pose_ref, "pose_ref")))


def error_coordinates_unchecked(pose, pose_ref) -> PolarError:
    """error_coordinates for poses already validated by as_pose (skips the checks, for speed)."""
    return _polar_coordinates(*_offset_to_origin(pose, pose_ref))


def polar_kinematics(e: float, alpha: float, u) -> tuple[float, float, float]:
    """(e_dot, psi_dot, alpha_dot) of the platform for velocity u = (u1, u2), eqs. (30)-(32).

    e_dot = cos(alpha) u1, psi_dot = sin(alpha)/e u1, alpha_dot = -sin(alpha)/e u1 + u2.
    Singular at e = 0 (psi and alpha are undefined there); the caller keeps e > 0.
    """
    u1, u2 = float(u[0]), float(u[1])
    s = math.sin(alpha)
    return math.cos(alpha) * u1, s / e * u1, -s / e * u1 + u2
