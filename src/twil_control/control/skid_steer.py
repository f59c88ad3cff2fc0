"""Skid-steer kinematics of qbot: the qbot report's Section 1 (configuration kinematic model) and
Section 2 (motor input commands), with Section 2's matrix inverted from Section 1 rather than as
printed (its signs of c would turn a left command into a right turn; docs/qbot.md).

Pure math, numpy only. REP 103 conventions; wheel speeds in rad/s, positive when they drive the
robot forward. Functions take scalars or numpy arrays (broadcast); scalars give Python floats.
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
    "report_printed_motor_matrix",
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


def report_printed_motor_matrix(r: float, c: float) -> np.ndarray:
    """The Section 2 matrix exactly as the qbot report prints it: ``(1/r) [[1, c], [1, -c]]``.

    Kept only to document the defect: ``forward_matrix(r, c) @ report_printed_motor_matrix(r, c)``
    is ``diag(1, -1)``, i.e. the printed commands reproduce ``v`` but invert ``w``. Do not
    use it to drive a robot.
    """
    r, c = _check_geometry(r, c)
    return np.array([[1.0, c], [1.0, -c]]) / r


def wheel_speeds(v, w, r: float, c: float):
    """Motor input commands in velocity mode (qbot report, Section 2, sign of ``c`` corrected).

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
    """Body velocity from wheel speeds (qbot report, Section 1, the ``eta`` of the CKM).

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
    """Configuration kinematic model ``q_dot = S(q) eta`` (qbot report, Section 1).

    ``S(q) = [[cos th, 0], [sin th, 0], [0, 1]]``, ``eta = [v_x, w]``, so
    ``X_dot = v cos th``, ``Y_dot = v sin th``, ``th_dot = w`` (no lateral velocity:
    the qbot report sets ``x_ICR = 0`` and ``v_y = 0``).

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
