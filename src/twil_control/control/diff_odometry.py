"""Wheel odometry for a differential or skid-steer base (diff_drive_controller's Odometry role),
integrating the qbot report's Section 1 kinematic model from wheel angles.

Pure math; the step is a compiled function (numba) that the cart controller's update calls
too. As ros_controllers' odometry.cpp: an exact arc, or second-order Runge-Kutta for turns too
small to divide by, and velocities averaged over a rolling window. Where it differs from ROS,
and the effective separation of a skid-steer base: docs/formulas.md, "Wheel odometry".
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
from numba import njit

from twil_control.errors import TwilControlError

from .floats import as_float

__all__ = [
    "OdometryError",
    "WheelOdometry",
    "integrate_exact",
    "integrate_runge_kutta2",
    "odometry_step",
    "ODO_SIZE",
]

EXACT_INTEGRATION_THRESHOLD = 1e-6
"""|dtheta| (rad) below which the RK2 step replaces the exact arc, as in ROS."""

MIN_VELOCITY_DT = 1e-4
"""Updates closer than this (s) do not feed the velocity estimate, as in ROS."""


class OdometryError(TwilControlError, ValueError):
    """Invalid odometry parameter or input (a ValueError)."""


def _finite(value, name: str) -> float:
    f = as_float(value)
    if not math.isfinite(f):
        raise OdometryError(f"{name} = {value!r} must be a finite number")
    return f


def _positive(value, name: str) -> float:
    f = _finite(value, name)
    if f <= 0.0:
        raise OdometryError(f"{name} = {value!r} must be > 0 (metres)")
    return f


@njit(cache=True, nogil=True)
def integrate_runge_kutta2(x, y, heading, ds, dtheta):
    """One RK2 (midpoint) step of ``q_dot = S(q) eta`` (qbot report, Section 1).

    ``x += ds cos(th + dth/2)``, ``y += ds sin(th + dth/2)``, ``th += dth``.
    """
    direction = heading + 0.5 * dtheta
    return x + ds * math.cos(direction), y + ds * math.sin(direction), heading + dtheta


@njit(cache=True, nogil=True)
def integrate_exact(x, y, heading, ds, dtheta):
    """Exact integration of ``q_dot = S(q) eta`` (qbot report, Section 1) for constant ``eta``.

    A circular arc of radius ``R = ds / dth``: ``x += R (sin(th + dth) - sin th)``,
    ``y -= R (cos(th + dth) - cos th)``. Falls back to :func:`integrate_runge_kutta2` when
    ``|dth| < 1e-6``.
    """
    if abs(dtheta) < EXACT_INTEGRATION_THRESHOLD:
        return integrate_runge_kutta2(x, y, heading, ds, dtheta)
    radius = ds / dtheta
    new_heading = heading + dtheta
    return (
        x + radius * (math.sin(new_heading) - math.sin(heading)),
        y - radius * (math.cos(new_heading) - math.cos(heading)),
        new_heading,
    )


# odometry_step's state array: x, y, heading (continuous), the last left and right wheel angles,
# and 1 once the first angles are recorded
ODO_X, ODO_Y, ODO_HEADING, ODO_LEFT, ODO_RIGHT, ODO_STARTED = range(6)
ODO_SIZE = 6


@njit(cache=True, nogil=True)
def odometry_step(odo, left, right, wheel_radius, wheel_separation):
    """The pose update of one odometry step, in the state array `odo` (ODO_* layout): the first
    call records the wheel angles (rad) and returns (0, 0); later ones move the pose by the
    increments, ``ds = r (d_phi_L + d_phi_R) / 2`` and ``dth = r (d_phi_R - d_phi_L) / b``
    (Section 1's eta times the step), integrated by :func:`integrate_exact`, and return
    (ds, dth)."""
    if odo[ODO_STARTED] == 0.0:
        odo[ODO_LEFT], odo[ODO_RIGHT], odo[ODO_STARTED] = left, right, 1.0
        return 0.0, 0.0
    d_left = wheel_radius * (left - odo[ODO_LEFT])
    d_right = wheel_radius * (right - odo[ODO_RIGHT])
    odo[ODO_LEFT], odo[ODO_RIGHT] = left, right
    ds = 0.5 * (d_left + d_right)
    dtheta = (d_right - d_left) / wheel_separation
    odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING] = integrate_exact(
        odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING], ds, dtheta
    )
    return ds, dtheta


class WheelOdometry:
    """Pose and twist of a differential/skid-steer base from wheel angles (qbot report, Section 1).

    Args:
        wheel_radius: r (m), > 0.
        wheel_separation: distance between the left and right wheel contact lines (m), > 0
            (``2c`` in the qbot report; for skid-steer, the calibrated effective value).
        velocity_rolling_window_size: number of updates averaged for the velocities (>= 1).

    Attributes (read-only properties): ``x``, ``y``, ``heading`` (rad, continuous), ``yaw``
    (wrapped), ``linear`` (m/s), ``angular`` (rad/s), ``pose`` and ``twist`` tuples,
    ``initialized``, ``stamp`` (time of the last update, s).
    """

    def __init__(
        self, wheel_radius: float, wheel_separation: float, velocity_rolling_window_size: int = 10
    ) -> None:
        self.wheel_radius = _positive(wheel_radius, "wheel_radius")
        self.wheel_separation = _positive(wheel_separation, "wheel_separation")
        if (
            isinstance(velocity_rolling_window_size, bool)
            or not isinstance(velocity_rolling_window_size, int)
            or velocity_rolling_window_size < 1
        ):
            raise OdometryError(
                f"velocity_rolling_window_size = {velocity_rolling_window_size!r} must be an int >= 1"
            )
        self._window = velocity_rolling_window_size
        self._linear_acc: deque[float] = deque(maxlen=self._window)
        self._angular_acc: deque[float] = deque(maxlen=self._window)
        self._odo = np.zeros(ODO_SIZE)
        self._stamp: float | None = None

    # -- state ---------------------------------------------------------------------------
    @property
    def x(self) -> float:
        return float(self._odo[ODO_X])

    @property
    def y(self) -> float:
        return float(self._odo[ODO_Y])

    @property
    def heading(self) -> float:
        """Heading (rad), continuous: it keeps counting after a full turn."""
        return float(self._odo[ODO_HEADING])

    @property
    def yaw(self) -> float:
        """Heading wrapped to ``[-pi, pi)``."""
        return (self.heading + math.pi) % (2.0 * math.pi) - math.pi

    @property
    def linear(self) -> float:
        """Forward velocity (m/s), rolling mean of the last updates."""
        return sum(self._linear_acc) / len(self._linear_acc) if self._linear_acc else 0.0

    @property
    def angular(self) -> float:
        """Yaw rate (rad/s), rolling mean of the last updates."""
        return sum(self._angular_acc) / len(self._angular_acc) if self._angular_acc else 0.0

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.x, self.y, self.heading

    @property
    def twist(self) -> tuple[float, float]:
        return self.linear, self.angular

    @property
    def initialized(self) -> bool:
        return self._stamp is not None

    @property
    def stamp(self) -> float | None:
        return self._stamp

    @property
    def velocity_rolling_window_size(self) -> int:
        return self._window

    # -- updates -------------------------------------------------------------------------
    def update(self, left_pos: float, right_pos: float, t: float) -> bool:
        """Integrate from new wheel angles ``left_pos``, ``right_pos`` (rad) at time ``t`` (s).

        The first call (and the first after :meth:`reset`) only records the angles and
        time, and returns False. Later calls move the pose by the increments (Section 1's
        ``eta`` times the step, integrated exactly or by RK2) and return True if the
        velocity estimate was updated too (``t`` at least 0.1 ms after the previous update).

        Raises:
            OdometryError: (a ValueError) for NaN/inf inputs or ``t`` before the last update.
        """
        left = _finite(left_pos, "left_pos")
        right = _finite(right_pos, "right_pos")
        t = _finite(t, "t")
        if self._stamp is None:
            self._odo[ODO_STARTED] = 0.0
            odometry_step(self._odo, left, right, self.wheel_radius, self.wheel_separation)
            self._stamp = t
            return False
        if t < self._stamp:
            raise OdometryError(
                f"t = {t!r} is before the previous update at {self._stamp!r}; call reset() after a time jump"
            )
        ds, dtheta = odometry_step(self._odo, left, right, self.wheel_radius, self.wheel_separation)
        dt = t - self._stamp
        if dt < MIN_VELOCITY_DT:
            return False
        self._stamp = t
        self._linear_acc.append(ds / dt)
        self._angular_acc.append(dtheta / dt)
        return True

    def update_open_loop(self, linear: float, angular: float, t: float) -> bool:
        """Integrate commanded velocities instead of measured wheel angles (ROS's
        ``updateOpenLoop``): the twist is set to the command, not averaged.

        The first call after construction or :meth:`reset` only records ``t``.
        """
        linear = _finite(linear, "linear")
        angular = _finite(angular, "angular")
        t = _finite(t, "t")
        if self._stamp is None:
            self._stamp = t
            return False
        if t < self._stamp:
            raise OdometryError(f"t = {t!r} is before the previous update at {self._stamp!r}")
        dt = t - self._stamp
        self._stamp = t
        odo = self._odo
        odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING] = integrate_exact(
            odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING], linear * dt, angular * dt
        )
        self._linear_acc.clear()
        self._angular_acc.clear()
        self._linear_acc.append(linear)
        self._angular_acc.append(angular)
        return True

    def reset(self, x: float = 0.0, y: float = 0.0, heading: float = 0.0) -> None:
        """Set the pose, clear the velocity window; the next update re-initialises."""
        self._odo[:] = 0.0
        self._odo[ODO_X] = _finite(x, "x")
        self._odo[ODO_Y] = _finite(y, "y")
        self._odo[ODO_HEADING] = _finite(heading, "heading")
        self._linear_acc.clear()
        self._angular_acc.clear()
        self._stamp = None

    def __repr__(self) -> str:
        return (
            f"WheelOdometry(x={self.x:.4f}, y={self.y:.4f}, heading={self.heading:.4f}, "
            f"linear={self.linear:.4f}, angular={self.angular:.4f})"
        )
