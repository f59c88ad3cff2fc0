"""PID with integral clamp and optional anti-windup (control_toolbox::Pid of ROS 1).

Pure math, no numpy needed. The conventions, the clamp parameters and the one place it differs
from control_toolbox (the anti-windup clamp is applied, not discarded): docs/formulas.md, "PID".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from twil_control.errors import InputError


@dataclass
class PidGains:
    p: float = 0.0
    i: float = 0.0
    d: float = 0.0
    i_max: float = 0.0
    i_min: float = 0.0
    antiwindup: bool = False

    @classmethod
    def from_clamp(
        cls, p: float = 0.0, i: float = 0.0, d: float = 0.0, i_clamp: float = 0.0, antiwindup: bool = False
    ) -> PidGains:
        return cls(p, i, d, abs(i_clamp), -abs(i_clamp), antiwindup)


class Pid:
    """control_toolbox::Pid: a discrete PID with the integral term clamped to [i_min, i_max]."""

    def __init__(
        self,
        p: float = 0.0,
        i: float = 0.0,
        d: float = 0.0,
        i_clamp: float = 0.0,
        antiwindup: bool = False,
        *,
        i_min: float | None = None,
        i_max: float | None = None,
    ) -> None:
        self.gains = PidGains.from_clamp(p, i, d, i_clamp, antiwindup)
        if i_max is not None:
            self.gains.i_max = float(i_max)
        if i_min is not None:
            self.gains.i_min = float(i_min)
        if self.gains.i_min > self.gains.i_max:
            raise InputError(
                f"PID integral clamp is empty: i_min {self.gains.i_min} > i_max {self.gains.i_max}"
            )
        self.reset()

    def reset(self) -> None:
        """Zero the integral and the error memory (Pid::reset, called by controllers' starting())."""
        self.p_error_last = 0.0
        self.p_error = 0.0
        self.i_error = 0.0
        self.d_error = 0.0
        self.cmd = 0.0

    def compute_command(self, error: float, error_dot: float, dt: float) -> float:
        """The command for `error` and its rate `error_dot` after `dt` seconds
        (Pid::computeCommand(error, error_dot, dt))."""
        if not (dt > 0.0) or not math.isfinite(error) or not math.isfinite(error_dot):
            return 0.0
        g = self.gains
        self.p_error, self.d_error = error, error_dot
        self.i_error += dt * error
        if g.antiwindup and g.i != 0.0:
            self.i_error = min(max(self.i_error, g.i_min / abs(g.i)), g.i_max / abs(g.i))
            i_term = g.i * self.i_error
        else:
            i_term = min(max(g.i * self.i_error, g.i_min), g.i_max)
        self.cmd = g.p * error + i_term + g.d * error_dot
        return self.cmd

    def compute_command_from_error(self, error: float, dt: float) -> float:
        """Pid::computeCommand(error, dt): the error rate is (error - last error) / dt."""
        if not (dt > 0.0) or not math.isfinite(error):
            return 0.0
        error_dot = (error - self.p_error_last) / dt
        self.p_error_last = error
        return self.compute_command(error, error_dot, dt)

    def computeCommand(self, error: float, *args: float) -> float:  # noqa: N802 (ROS spelling)
        """The two C++ overloads: (error, dt) or (error, error_dot, dt)."""
        if len(args) == 1:
            return self.compute_command_from_error(error, args[0])
        return self.compute_command(error, *args)
