"""Skid-steer kinematics of the four-wheeled robot "qbot" (second seed).

Pure math, numpy only. Every equation cites the seed's section:

* Section 1, "Configuration Kinematic Model": ``q_dot = S(q) eta`` with
  ``S(q) = [[cos th, 0], [sin th, 0], [0, 1]]`` and
  ``eta = [v_x, w] = r [(w_L + w_R)/2, (-w_L + w_R)/(2c)]``, where ``r`` is the wheel
  radius and ``2c`` the track width (the simplified Kozlowski-Pazderski model with
  ``x_ICR = 0`` and ``v_y = 0``).
* Section 2, "Motor Input Commands": the inverse of the Section 1 map,
  ``[w_L, w_R] = (1/r) [[1, -c], [1, c]] [v_x, w]``.

The seed *prints* the Section 2 matrix as ``(1/r) [[1, c], [1, -c]]``: the signs of ``c``
are swapped relative to its own forward model, so a command to turn left (``w > 0``)
would turn the robot right. This module inverts the forward model instead; see
:func:`seed_printed_motor_matrix` and ``tests/test_skid_steer.py``.

Conventions (REP 103): ``v`` forward in m/s, ``w`` counter-clockwise (about +z) in rad/s,
wheel speeds in rad/s, positive when the wheel drives the robot forward (the seed's own
assumption in Section 2). On qbot the wheels sit at ``y = +-0.18 m``, so ``c = 0.18`` and
the track width ``2c = 0.36 m`` (the gazebo plugin's ``wheelSeparation``).

Functions accept scalars or numpy arrays (broadcast); scalars in give Python floats out.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from twil_control.errors import TwilControlError

from .floats import as_float

__all__ = [
    "SkidSteerError",
    "body_velocity",
    "configuration_rate",
    "forward_matrix",
    "motor_matrix",
    "seed_printed_motor_matrix",
    "wheel_speeds",
]


class SkidSteerError(TwilControlError, ValueError):
    """A skid-steer geometry parameter is invalid (a ValueError)."""


def _check_geometry(r: float, c: float) -> tuple[float, float]:
    """Validate the wheel radius ``r`` and half track ``c``: finite and > 0."""
    checked = []
    for name, meaning, value in (
        ("r", "wheel radius (not the diameter)", r),
        ("c", "half track width (the track width is 2c)", c),
    ):
        f = as_float(value)
        if not math.isfinite(f) or f <= 0.0:
            raise SkidSteerError(
                f"{name} = {value!r} is invalid: the {meaning} must be a finite number > 0 in metres"
            )
        checked.append(f)
    return checked[0], checked[1]


def _out(a: np.ndarray):
    """Return a Python float for 0-d results, the array otherwise."""
    return float(a) if np.ndim(a) == 0 else a


def forward_matrix(r: float, c: float) -> np.ndarray:
    """Section 1 map from wheel speeds to body velocity.

    ``[v_x, w] = F [w_L, w_R]`` with ``F = r [[1/2, 1/2], [-1/(2c), 1/(2c)]]``.
    """
    r, c = _check_geometry(r, c)
    return r * np.array([[0.5, 0.5], [-0.5 / c, 0.5 / c]])


def motor_matrix(r: float, c: float) -> np.ndarray:
    """Section 2 motor-command matrix, the exact inverse of :func:`forward_matrix`.

    ``[w_L, w_R] = M [v_x, w]`` with ``M = (1/r) [[1, -c], [1, c]]``.
    """
    r, c = _check_geometry(r, c)
    return np.array([[1.0, -c], [1.0, c]]) / r


def seed_printed_motor_matrix(r: float, c: float) -> np.ndarray:
    """The Section 2 matrix exactly as the seed prints it: ``(1/r) [[1, c], [1, -c]]``.

    Kept only to document the defect: ``forward_matrix(r, c) @ seed_printed_motor_matrix(r, c)``
    is ``diag(1, -1)``, i.e. the printed commands reproduce ``v`` but invert ``w``. Do not
    use it to drive a robot.
    """
    r, c = _check_geometry(r, c)
    return np.array([[1.0, c], [1.0, -c]]) / r


def wheel_speeds(v, w, r: float, c: float):
    """Motor input commands in velocity mode (seed Section 2, sign of ``c`` corrected).

    ``w_L = (v - c w) / r`` and ``w_R = (v + c w) / r``, the inverse of Section 1's
    ``eta = r [(w_L + w_R)/2, (-w_L + w_R)/(2c)]``.

    Args:
        v: forward body velocity v_x (m/s), scalar or array.
        w: yaw rate (rad/s, counter-clockwise positive), scalar or array.
        r: wheel radius (m), > 0.
        c: half the track width (m), > 0; the track width is ``2c``.

    Returns:
        ``(w_left, w_right)`` wheel angular velocities in rad/s (positive drives forward).

    Raises:
        SkidSteerError: (a ValueError) if ``r`` or ``c`` is not a finite number > 0.
    """
    r, c = _check_geometry(r, c)
    left, right = motor_commands(np.asarray(v, dtype=float), np.asarray(w, dtype=float), r, c)
    return _out(left), _out(right)


@njit(cache=True, nogil=True)
def motor_commands(v, w, r, c):
    """``(w_L, w_R) = ((v - c w) / r, (v + c w) / r)`` (Section 2, sign of ``c`` corrected), for
    checked geometry: what :func:`wheel_speeds` computes, and the qbot drive's compiled update."""
    return (v - c * w) / r, (v + c * w) / r


def body_velocity(w_left, w_right, r: float, c: float):
    """Body velocity from wheel speeds (seed Section 1, the ``eta`` of the CKM).

    ``v_x = r (w_L + w_R) / 2`` and ``w = r (-w_L + w_R) / (2c)``.

    Args:
        w_left, w_right: wheel angular velocities (rad/s), scalars or arrays.
        r: wheel radius (m), > 0.
        c: half the track width (m), > 0.

    Returns:
        ``(v, w)``: forward velocity (m/s) and yaw rate (rad/s).

    Raises:
        SkidSteerError: (a ValueError) if ``r`` or ``c`` is not a finite number > 0.
    """
    r, c = _check_geometry(r, c)
    wl = np.asarray(w_left, dtype=float)
    wr = np.asarray(w_right, dtype=float)
    return _out(r * (wl + wr) / 2.0), _out(r * (wr - wl) / (2.0 * c))


def configuration_rate(theta, v, w):
    """Configuration kinematic model ``q_dot = S(q) eta`` (seed Section 1).

    ``S(q) = [[cos th, 0], [sin th, 0], [0, 1]]``, ``eta = [v_x, w]``, so
    ``X_dot = v cos th``, ``Y_dot = v sin th``, ``th_dot = w`` (no lateral velocity:
    the seed sets ``x_ICR = 0`` and ``v_y = 0``).

    Args:
        theta: heading th of the robot in the inertial frame (rad), scalar or array.
        v: forward velocity v_x (m/s).
        w: yaw rate (rad/s).

    Returns:
        ``(x_dot, y_dot, theta_dot)`` in m/s, m/s, rad/s.
    """
    theta = np.asarray(theta, dtype=float)
    v = np.asarray(v, dtype=float)
    w = np.asarray(w, dtype=float)
    x_dot = v * np.cos(theta)
    y_dot = v * np.sin(theta)
    theta_dot = w + np.zeros_like(x_dot)
    return _out(x_dot), _out(y_dot), _out(theta_dot)
