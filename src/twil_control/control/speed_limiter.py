"""Velocity, acceleration and jerk limits on a velocity command (diff_drive_controller's
SpeedLimiter role), applied to qbot's and TWIL's cmd_vel before the wheel commands.

Pure math; the limits are compiled functions (numba) that the qbot drive's update calls too.
As ros_controllers' speed_limiter.cpp: jerk, then acceleration, then velocity. Where it differs
(the jerk step, NaN refused, no Noetic deceleration limits): docs/formulas.md, "Speed limits".
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from twil_control.errors import TwilControlError

from .floats import as_float

__all__ = ["SpeedLimiter", "SpeedLimiterError", "clamp", "LIMIT_FIELDS", "limited"]

#: a limiter's settings as one float array (`SpeedLimiter.row`), flags as 0.0 / 1.0
LIMIT_FIELDS = (
    "has_velocity_limits",
    "min_velocity",
    "max_velocity",
    "has_acceleration_limits",
    "min_acceleration",
    "max_acceleration",
    "has_jerk_limits",
    "min_jerk",
    "max_jerk",
)


class SpeedLimiterError(TwilControlError, ValueError):
    """An invalid limit or input to :class:`SpeedLimiter` (a ValueError)."""


@njit(cache=True, nogil=True)
def clamp(x, lo, hi):
    """``min(max(lo, x), hi)``, as ``speed_limiter.cpp``'s ``clamp``."""
    return min(max(lo, x), hi)


@njit(cache=True, nogil=True)
def _scale(limit, dt):
    """``limit * dt`` with ``inf * 0 = 0`` (no change is possible in zero time)."""
    return 0.0 if dt == 0.0 else limit * dt


@njit(cache=True, nogil=True)
def jerk_limited(v, v0, v1, dt, j_min, j_max):
    """``v0 + (v0 - v1) + clamp((v - v0) - (v0 - v1), j_min dt^2, j_max dt^2)``."""
    dv0 = v0 - v1
    dt2 = dt * dt
    return v0 + dv0 + clamp((v - v0) - dv0, _scale(j_min, dt2), _scale(j_max, dt2))


@njit(cache=True, nogil=True)
def acceleration_limited(v, v0, dt, a_min, a_max):
    """``v0 + clamp(v - v0, a_min dt, a_max dt)``."""
    return v0 + clamp(v - v0, _scale(a_min, dt), _scale(a_max, dt))


@njit(cache=True, nogil=True)
def limited(v, v0, v1, dt, row):
    """The limited command: jerk, then acceleration, then velocity limits, those enabled in
    `row` (LIMIT_FIELDS order); v0, v1 the two previous limited commands. Finite inputs, dt >= 0."""
    if row[6] != 0.0:
        v = jerk_limited(v, v0, v1, dt, row[7], row[8])
    if row[3] != 0.0:
        v = acceleration_limited(v, v0, dt, row[4], row[5])
    if row[0] != 0.0:
        v = clamp(v, row[1], row[2])
    return v


def _finite(value, name: str) -> float:
    f = as_float(value)
    if not math.isfinite(f):
        raise SpeedLimiterError(
            f"{name} = {value!r} is not a finite number; the command should be ignored "
            f"(diff_drive_controller drops NaN commands) and the previous one kept"
        )
    return f


class SpeedLimiter:
    """Limits one velocity component (linear/x or angular/z) like diff_drive_controller.

    Args:
        has_velocity_limits: clamp to ``[min_velocity, max_velocity]``.
        has_acceleration_limits: clamp ``(v - v0)/dt`` to ``[min_acceleration, max_acceleration]``.
        min_velocity, max_velocity: velocity bounds (m/s or rad/s). ``min_velocity=None``
            means ``-max_velocity`` (the ROS parameter default).
        min_acceleration, max_acceleration: acceleration bounds; ``min_acceleration=None``
            means ``-max_acceleration``.
        has_jerk_limits, min_jerk, max_jerk: optional jerk limits (``min_jerk=None`` means
            ``-max_jerk``); they need the command before the previous one (``v_prev2``).

    Raises:
        SpeedLimiterError: (a ValueError) for NaN limits or a minimum above its maximum.
    """

    def __init__(
        self,
        has_velocity_limits: bool = False,
        has_acceleration_limits: bool = False,
        min_velocity: float | None = None,
        max_velocity: float = 0.0,
        min_acceleration: float | None = None,
        max_acceleration: float = 0.0,
        *,
        has_jerk_limits: bool = False,
        min_jerk: float | None = None,
        max_jerk: float = 0.0,
    ) -> None:
        self.has_velocity_limits = bool(has_velocity_limits)
        self.has_acceleration_limits = bool(has_acceleration_limits)
        self.has_jerk_limits = bool(has_jerk_limits)
        self.min_velocity, self.max_velocity = self._pair(
            "velocity", min_velocity, max_velocity, self.has_velocity_limits
        )
        self.min_acceleration, self.max_acceleration = self._pair(
            "acceleration", min_acceleration, max_acceleration, self.has_acceleration_limits
        )
        self.min_jerk, self.max_jerk = self._pair("jerk", min_jerk, max_jerk, self.has_jerk_limits)
        #: the settings as one array (LIMIT_FIELDS), what `limited` reads
        self.row = np.array([float(getattr(self, name)) for name in LIMIT_FIELDS])
        self._last = (0.0, 0.0)  # (v0, v1) for step()

    @staticmethod
    def _pair(what: str, lo, hi, enabled: bool) -> tuple[float, float]:
        def num(value, name):
            f = as_float(value)
            if math.isnan(f):
                raise SpeedLimiterError(f"{name} = {value!r} must be a number (inf allowed)")
            return f

        hi_f = num(hi, f"max_{what}")
        lo_f = -hi_f if lo is None else num(lo, f"min_{what}")
        if enabled and lo_f > hi_f:
            raise SpeedLimiterError(
                f"min_{what} = {lo_f!r} exceeds max_{what} = {hi_f!r}; "
                f"set min_{what} <= max_{what} (typically min = -max)"
            )
        return lo_f, hi_f

    # -- the three limits, as speed_limiter.cpp ----------------------------------------
    def limit_velocity(self, v: float) -> float:
        """Clamp ``v`` to ``[min_velocity, max_velocity]`` if velocity limits are on."""
        v = _finite(v, "v")
        if self.has_velocity_limits:
            v = clamp(v, self.min_velocity, self.max_velocity)
        return v

    def limit_acceleration(self, v: float, v_prev: float, dt: float) -> float:
        """``v0 + clamp(v - v0, min_acceleration dt, max_acceleration dt)`` if enabled."""
        v, v0, dt = _finite(v, "v"), _finite(v_prev, "v_prev"), self._dt(dt)
        if self.has_acceleration_limits:
            v = acceleration_limited(v, v0, dt, self.min_acceleration, self.max_acceleration)
        return v

    def limit_jerk(self, v: float, v_prev: float, v_prev2: float, dt: float) -> float:
        """Bound the change of the velocity step, ``(v - v0) - (v0 - v1)``, by ``jerk dt^2``."""
        v, v0, v1 = _finite(v, "v"), _finite(v_prev, "v_prev"), _finite(v_prev2, "v_prev2")
        dt = self._dt(dt)
        if self.has_jerk_limits:
            v = jerk_limited(v, v0, v1, dt, self.min_jerk, self.max_jerk)
        return v

    def limit(self, v: float, v_prev: float, dt: float, v_prev2: float | None = None) -> float:
        """The limited command: jerk, then acceleration, then velocity limits.

        Args:
            v: the requested velocity.
            v_prev: the previous (limited) command, ROS's ``v0``.
            dt: time since the previous command (s), >= 0.
            v_prev2: the command before ``v_prev``, ROS's ``v1``; needed only with jerk
                limits (``None`` then means ``v_prev``: zero previous acceleration).

        Returns:
            The limited velocity (a float).

        Raises:
            SpeedLimiterError: (a ValueError) for NaN/inf inputs or ``dt < 0``.
        """
        v = _finite(v, "v")
        v0 = _finite(v_prev, "v_prev")
        v1 = v0 if v_prev2 is None else _finite(v_prev2, "v_prev2")
        return float(limited(v, v0, v1, self._dt(dt), self.row))

    def factor(self, v: float, v_limited: float) -> float:
        """ROS's return value of ``limit``: ``v_limited / v``, or 1 when ``v == 0``."""
        return v_limited / v if v != 0.0 else 1.0

    # -- stateful convenience (diff_drive_controller keeps last0_cmd, last1_cmd) --------
    def step(self, v: float, dt: float) -> float:
        """Limit ``v`` against the commands this object returned before, and remember it."""
        v0, v1 = self._last
        out = self.limit(v, v0, dt, v1)
        self._last = (out, v0)
        return out

    def reset(self, v: float = 0.0) -> None:
        """Forget the history of :meth:`step`; the robot is at rest at ``v``."""
        v = _finite(v, "v")
        self._last = (v, v)

    @staticmethod
    def _dt(dt) -> float:
        dt = _finite(dt, "dt")
        if dt < 0.0:
            raise SpeedLimiterError(f"dt = {dt!r} must be >= 0 (seconds since the previous command)")
        return dt

    def __repr__(self) -> str:
        return (
            f"SpeedLimiter(velocity={self.has_velocity_limits} [{self.min_velocity}, "
            f"{self.max_velocity}], acceleration={self.has_acceleration_limits} "
            f"[{self.min_acceleration}, {self.max_acceleration}], jerk={self.has_jerk_limits} "
            f"[{self.min_jerk}, {self.max_jerk}])"
        )
