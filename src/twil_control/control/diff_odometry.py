"""Wheel odometry for a differential or skid-steer base (diff_drive_controller's Odometry role),
integrating the qbot report's Section 1 kinematic model from wheel angles.

Pure math; the step is a compiled function (numba) that the cart controller's update calls
too. As ros_controllers' odometry.cpp: an exact arc, or second-order Runge-Kutta for turns too
small to divide by, and velocities averaged over a rolling window. Where it differs from ROS,
and the effective separation of a skid-steer base: docs/formulas.md, "Wheel odometry".
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from twil_control.errors import TwilControlError

from .floats import as_float

__all__ = [
    "OdometryError",
    "WheelOdometry",
    "integrate_exact",
    "integrate_runge_kutta2",
    "odometry_open_loop",
    "odometry_step",
    "odometry_update",
    "rolling_mean",
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


# The odometry's state array: x, y, heading (continuous), the last left and right wheel angles,
# 1 once the first angles are recorded (odometry_step uses these six); then the time of the last
# velocity update, 1 once there is one, and the rolling window's sample count and next slot.
ODO_X, ODO_Y, ODO_HEADING, ODO_LEFT, ODO_RIGHT, ODO_STARTED = range(6)
ODO_STAMP, ODO_STAMPED, ODO_COUNT, ODO_NEXT = range(6, 10)
ODO_SIZE = 10

#: odometry_update's and odometry_open_loop's results
POSE_ONLY, VELOCITY_UPDATED, TIME_BACKWARDS, NOT_FINITE = 0, 1, -1, -2


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


@njit(cache=True, nogil=True)
def _rolling_push(odo, window, linear, angular):
    """Add one (linear, angular) velocity sample to the rolling window, a (2, N) array whose
    oldest sample the next one replaces once N are held."""
    n = window.shape[1]
    k = int(odo[ODO_NEXT])
    window[0, k] = linear
    window[1, k] = angular
    odo[ODO_NEXT] = (k + 1) % n
    odo[ODO_COUNT] = min(odo[ODO_COUNT] + 1.0, float(n))


@njit(cache=True, nogil=True)
def rolling_mean(odo, window, row):
    """The mean of the window's samples of `row` (0 linear, 1 angular), summed oldest first;
    0 with no sample."""
    count = int(odo[ODO_COUNT])
    if count == 0:
        return 0.0
    n = window.shape[1]
    start = (int(odo[ODO_NEXT]) - count) % n
    total = 0.0
    for k in range(count):
        total += window[row, (start + k) % n]
    return total / count


@njit(cache=True, nogil=True)
def odometry_update(odo, window, left, right, t, wheel_radius, wheel_separation):
    """One update from wheel angles at time t (WheelOdometry.update): the first (after a reset)
    records the angles and t (POSE_ONLY); later ones step the pose (odometry_step) and, when t
    is at least MIN_VELOCITY_DT after the last velocity update, add ds/dt and dth/dt to the
    rolling window (VELOCITY_UPDATED). A t before the last update is TIME_BACKWARDS, a
    non-finite input NOT_FINITE; both leave the state as it was."""
    if not (math.isfinite(left) and math.isfinite(right) and math.isfinite(t)):
        return NOT_FINITE
    if odo[ODO_STAMPED] == 0.0:
        odo[ODO_STARTED] = 0.0
        odometry_step(odo, left, right, wheel_radius, wheel_separation)
        odo[ODO_STAMP], odo[ODO_STAMPED] = t, 1.0
        return POSE_ONLY
    if t < odo[ODO_STAMP]:
        return TIME_BACKWARDS
    ds, dtheta = odometry_step(odo, left, right, wheel_radius, wheel_separation)
    dt = t - odo[ODO_STAMP]
    if dt < MIN_VELOCITY_DT:
        return POSE_ONLY
    odo[ODO_STAMP] = t
    _rolling_push(odo, window, ds / dt, dtheta / dt)
    return VELOCITY_UPDATED


@njit(cache=True, nogil=True)
def odometry_open_loop(odo, window, linear, angular, t):
    """One open-loop update from commanded velocities (WheelOdometry.update_open_loop): the
    first records t; later ones integrate the command over the time since the last and make it
    the window's only sample. Results as odometry_update's."""
    if not (math.isfinite(linear) and math.isfinite(angular) and math.isfinite(t)):
        return NOT_FINITE
    if odo[ODO_STAMPED] == 0.0:
        odo[ODO_STAMP], odo[ODO_STAMPED] = t, 1.0
        return POSE_ONLY
    if t < odo[ODO_STAMP]:
        return TIME_BACKWARDS
    dt = t - odo[ODO_STAMP]
    odo[ODO_STAMP] = t
    odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING] = integrate_exact(
        odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING], linear * dt, angular * dt
    )
    odo[ODO_COUNT], odo[ODO_NEXT] = 0.0, 0.0
    _rolling_push(odo, window, linear, angular)
    return VELOCITY_UPDATED


def raise_for(status: int, t: float, odo: np.ndarray, what: str) -> None:
    """OdometryError for a TIME_BACKWARDS or NOT_FINITE result (nothing for the others)."""
    if status == TIME_BACKWARDS:
        raise OdometryError(
            f"t = {t!r} is before the previous update at {float(odo[ODO_STAMP])!r}; "
            "call reset() after a time jump"
        )
    if status == NOT_FINITE:
        raise OdometryError(f"{what} and t = {t!r} must be finite numbers")


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
        #: the state (ODO_* layout) and the rolling window of (linear, angular) samples: the
        #: arrays the compiled updates (odometry_update, diff_drive_kernel) work on
        self.state = np.zeros(ODO_SIZE)
        self.window = np.zeros((2, self._window))

    # -- state ---------------------------------------------------------------------------
    @property
    def x(self) -> float:
        return float(self.state[ODO_X])

    @property
    def y(self) -> float:
        return float(self.state[ODO_Y])

    @property
    def heading(self) -> float:
        """Heading (rad), continuous: it keeps counting after a full turn."""
        return float(self.state[ODO_HEADING])

    @property
    def yaw(self) -> float:
        """Heading wrapped to ``[-pi, pi)``."""
        return (self.heading + math.pi) % (2.0 * math.pi) - math.pi

    @property
    def linear(self) -> float:
        """Forward velocity (m/s), rolling mean of the last updates."""
        return float(rolling_mean(self.state, self.window, 0))

    @property
    def angular(self) -> float:
        """Yaw rate (rad/s), rolling mean of the last updates."""
        return float(rolling_mean(self.state, self.window, 1))

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.x, self.y, self.heading

    @property
    def twist(self) -> tuple[float, float]:
        return self.linear, self.angular

    @property
    def initialized(self) -> bool:
        return bool(self.state[ODO_STAMPED])

    @property
    def stamp(self) -> float | None:
        return float(self.state[ODO_STAMP]) if self.state[ODO_STAMPED] else None

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
        status = odometry_update(
            self.state, self.window, left, right, t, self.wheel_radius, self.wheel_separation
        )
        raise_for(status, t, self.state, "left_pos, right_pos")
        return status == VELOCITY_UPDATED

    def update_open_loop(self, linear: float, angular: float, t: float) -> bool:
        """Integrate commanded velocities instead of measured wheel angles (ROS's
        ``updateOpenLoop``): the twist is set to the command, not averaged.

        The first call after construction or :meth:`reset` only records ``t``.
        """
        linear = _finite(linear, "linear")
        angular = _finite(angular, "angular")
        t = _finite(t, "t")
        status = odometry_open_loop(self.state, self.window, linear, angular, t)
        raise_for(status, t, self.state, "linear, angular")
        return status == VELOCITY_UPDATED

    def reset(self, x: float = 0.0, y: float = 0.0, heading: float = 0.0) -> None:
        """Set the pose, clear the velocity window; the next update re-initialises."""
        self.state[:] = 0.0
        self.state[ODO_X] = _finite(x, "x")
        self.state[ODO_Y] = _finite(y, "y")
        self.state[ODO_HEADING] = _finite(heading, "heading")

    def __repr__(self) -> str:
        return (
            f"WheelOdometry(x={self.x:.4f}, y={self.y:.4f}, heading={self.heading:.4f}, "
            f"linear={self.linear:.4f}, angular={self.angular:.4f})"
        )
