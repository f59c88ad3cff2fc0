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

from twil_control.errors import InputError

__all__ = ["quintic", "held_reference", "SegmentChain"]


def quintic(q0, q1, duration: float, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, qd, qdd) at time t of the minimum-jerk segment from q0 to q1 over `duration`, at
    rest at both ends: s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5, tau = t / duration, clamped to
    [0, 1] (before the start: q0 at rest; after the end: q1 at rest)."""
    q0 = np.asarray(q0, dtype=float)
    dq = np.asarray(q1, dtype=float) - q0
    if not duration > 0.0:
        raise InputError(f"duration must be > 0 s (got {duration!r})")
    tau = min(max(t / duration, 0.0), 1.0)
    s = tau**3 * (10.0 + tau * (-15.0 + 6.0 * tau))
    sd = 30.0 * tau**2 * (1.0 - tau) ** 2 / duration
    sdd = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / duration**2
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


class SegmentChain:
    """A program of joint segments, each (time, target, duration): from its time, the reference
    goes from where the previous segment had it then (the chain's start for the first) to the
    target on a quintic path in `duration` s; duration 0 is a step to the target."""

    def __init__(self, segments: list[tuple[float, np.ndarray, float]]) -> None:
        times = [s[0] for s in segments]
        if not segments or any(b <= a for a, b in zip(times, times[1:])):
            raise InputError(f"segment times must be increasing (got {times})")
        if any(not d >= 0.0 for _, _, d in segments):
            raise InputError("segment durations must be >= 0 s")
        self.segments = [(float(t), np.asarray(q, dtype=float), float(d)) for t, q, d in segments]
        self._starts: list[np.ndarray] | None = None

    @property
    def started(self) -> bool:
        return self._starts is not None

    def start_from(self, q0) -> None:
        """Fix where the first segment starts (the joints' measured position)."""
        starts = [np.asarray(q0, dtype=float)]
        for prev, seg in zip(self.segments, self.segments[1:]):
            starts.append(self._along(prev, starts[-1], seg[0] - prev[0])[0])
        self._starts = starts

    def index(self, t: float) -> int | None:
        """The segment in force at time t (None before the first)."""
        k = None
        for i, seg in enumerate(self.segments):
            if seg[0] <= t + 1e-9:
                k = i
        return k

    def sample(self, t: float):
        """(segment index, q, qd, qdd) at time t; None before the first segment or before start_from."""
        k = self.index(t)
        if k is None or self._starts is None:
            return None
        seg = self.segments[k]
        return (k, *self._along(seg, self._starts[k], t - seg[0]))

    @staticmethod
    def _along(seg, start, dt: float):
        _, target, duration = seg
        if duration == 0.0:
            zero = np.zeros_like(target)
            return target, zero, zero
        return quintic(start, target, duration, dt)
