"""PWM velocity controller of qbot (the qbot report's Section 3, Listing 1, without its defects).

Pure math, all integers (the mapping is compiled, numba, for the qbot drive's update). Listing
1's four defects, why the period is 254 ticks (exactly 0 V at zero, full scale, an 8-bit
register) and the empty-phase rule: docs/qbot.md, "The PWM".
"""

from __future__ import annotations

import math
from collections.abc import Iterator

from numba import njit

from twil_control.errors import TwilControlError

from .floats import as_float

__all__ = [
    "DEFAULT_PERIOD_TICKS",
    "PwmError",
    "PwmVelocityController",
    "duty_to_average_voltage",
    "saturate_velocity",
    "velocity_to_duty",
    "duty_of",
    "average_voltage",
]

DEFAULT_PERIOD_TICKS = 254
"""Timer ticks per PWM period: the largest even period whose duty fits 8 bits."""


class PwmError(TwilControlError, ValueError):
    """An invalid PWM command or configuration (a ValueError)."""


def _finite(value, what: str, hint: str = "") -> float:
    """``float(value)`` if finite, else PwmError naming ``what`` and the value."""
    f = as_float(value)
    if not math.isfinite(f):
        raise PwmError(f"{what} must be a finite number, got {value!r}{hint}")
    return f


def _check_period(period_ticks) -> int:
    if (
        isinstance(period_ticks, bool)
        or not isinstance(period_ticks, int)
        or period_ticks < 2
        or period_ticks > 254
        or period_ticks % 2
    ):
        raise PwmError(
            f"period_ticks = {period_ticks!r} is invalid: it must be an even int in 2..254 "
            f"(even so that zero velocity is exactly 0 V, <= 254 so the duty fits 8 bits); "
            f"the default is {DEFAULT_PERIOD_TICKS}"
        )
    return period_ticks


@njit(cache=True, nogil=True)
def cap_velocity(vel):
    """A normalised velocity clamped to ``[-1, 1]`` (Listing 1's "cap velocity", corrected)."""
    return min(1.0, max(-1.0, vel))


@njit(cache=True, nogil=True)
def duty_of(vel, period):
    """``P/2 + round_half_away_from_zero(clamp(vel, -1, 1) * P/2)``, clamped to ``0..P``: the
    duty of a finite velocity command for a checked even period (docs/qbot.md, "The PWM")."""
    half = period // 2
    x = cap_velocity(vel) * half
    n = int(math.floor(abs(x) + 0.5))
    return min(period, max(0, half + (n if x >= 0.0 else -n)))


@njit(cache=True, nogil=True)
def average_voltage(duty, period, v_high, v_low):
    """``(duty * v_high + (P - duty) * v_low) / P``, the average output over one period."""
    return (duty * v_high + (period - duty) * v_low) / period


def saturate_velocity(vel) -> float:
    """Cap a normalised velocity to ``[-1, 1]`` (qbot report, Section 3, Listing 1 "cap velocity").

    Listing 1 meant ``vel = vel / |vel|`` for ``|vel| > 1``; this does it with a float
    clamp (1.5 -> 1.0, -1.5 -> -1.0). NaN and +-inf raise :class:`PwmError`.
    """
    v = _finite(
        vel,
        "velocity command vel",
        "; the command was refused and the previous duty kept (send a value in [-1, 1])",
    )
    return float(cap_velocity(v))


def velocity_to_duty(vel, period_ticks: int = DEFAULT_PERIOD_TICKS) -> int:
    """Normalised velocity to high-phase ticks (qbot report, Section 3, Listing 1, corrected).

    ``duty = P/2 + round_half_away_from_zero(sat(vel) * P/2)``, an int in ``0..P``;
    ``P/2`` at ``vel = 0`` (exactly 0 V), ``P`` at ``vel >= 1``, ``0`` at ``vel <= -1``.

    Raises:
        PwmError: (a ValueError) for NaN/inf ``vel`` or an invalid ``period_ticks``.
    """
    period = _check_period(period_ticks)
    return int(duty_of(saturate_velocity(vel), period))


def duty_to_average_voltage(
    duty: int, period_ticks: int = DEFAULT_PERIOD_TICKS, v_high: float = 5.0, v_low: float = -5.0
) -> float:
    """Average output voltage over one PWM period (qbot report, Section 3).

    ``V = (duty * v_high + (P - duty) * v_low) / P``: the high phase lasts ``duty`` ticks at
    ``v_high``, the low phase ``P - duty`` ticks at ``v_low``.
    """
    period = _check_period(period_ticks)
    if isinstance(duty, bool) or not isinstance(duty, int) or not 0 <= duty <= period:
        raise PwmError(f"duty = {duty!r} must be an int in 0..{period} (period_ticks)")
    return float(average_voltage(duty, period, float(v_high), float(v_low)))


class PwmVelocityController:
    """Replica of Listing 1 (qbot report, Section 3) without its defects.

    ``set_velocity(vel)`` maps a normalised velocity in ``[-1, 1]`` to an 8-bit duty; the
    waveform it stands for is ``high_ticks`` ticks at ``v_high`` then ``low_ticks`` ticks at
    ``v_low``, repeating every ``period_ticks`` ticks (the timer interrupt's job, see
    :meth:`level_at` and :meth:`waveform`). A new controller outputs 0 V (duty ``P/2``).

    Args:
        v_high: level of the high phase in volts (+5 V in the qbot report).
        v_low: level of the low phase in volts (-5 V in the qbot report); must be < ``v_high``.
        period_ticks: even int in 2..254 (default 254: docs/qbot.md, "The PWM").

    Attributes:
        duty (int): high-phase length in ticks, 0..period_ticks (so within 0..255).
    """

    def __init__(
        self, v_high: float = 5.0, v_low: float = -5.0, period_ticks: int = DEFAULT_PERIOD_TICKS
    ) -> None:
        self._period = _check_period(period_ticks)
        self.v_high = _finite(v_high, "v_high")
        self.v_low = _finite(v_low, "v_low")
        if not self.v_low < self.v_high:
            raise PwmError(
                f"v_low = {v_low!r} must be below v_high = {v_high!r} (the qbot report uses -5 V and +5 V)"
            )
        self.duty: int = self._period // 2
        self._velocity = 0.0

    # -- Listing 1: set_velocity -------------------------------------------------------
    def set_velocity(self, vel) -> int:
        """Set the normalised velocity and return the new duty (Listing 1 ``set_velocity``).

        ``|vel| > 1`` saturates; NaN or inf raises :class:`PwmError` and leaves the
        previous duty in place.
        """
        saturated = saturate_velocity(vel)
        self.duty = velocity_to_duty(saturated, self._period)
        self._velocity = saturated
        return self.duty

    @property
    def velocity(self) -> float:
        """The last accepted velocity command after saturation, in ``[-1, 1]``."""
        return self._velocity

    # -- the timer's phases ------------------------------------------------------------
    @property
    def period_ticks(self) -> int:
        """Ticks per PWM period (high + low)."""
        return self._period

    @property
    def high_ticks(self) -> int:
        """Ticks at ``v_high`` per period (the first phase; equals ``duty``)."""
        return self.duty

    @property
    def low_ticks(self) -> int:
        """Ticks at ``v_low`` per period (``period_ticks - duty``)."""
        return self._period - self.duty

    @property
    def voltage_step(self) -> float:
        """Average-voltage change per duty step, ``(v_high - v_low) / period_ticks``."""
        return (self.v_high - self.v_low) / self._period

    @property
    def average_voltage(self) -> float:
        """Average output voltage over one period in volts (0.0 exactly at zero velocity)."""
        return duty_to_average_voltage(self.duty, self._period, self.v_high, self.v_low)

    @property
    def ideal_voltage(self) -> float:
        """The unquantised target ``mid + vel * (v_high - v_low) / 2`` in volts."""
        mid = 0.5 * (self.v_high + self.v_low)
        return mid + self._velocity * 0.5 * (self.v_high - self.v_low)

    # -- the timer interrupt's role ----------------------------------------------------
    def level_at(self, tick: int) -> float:
        """Output level (volts) during timer tick ``tick`` (>= 0) for the current duty.

        Each period starts with the high phase: ticks ``0 .. high_ticks - 1`` (mod
        ``period_ticks``) are at ``v_high``, the rest at ``v_low``. An empty phase is
        skipped, so duty ``P`` is a constant ``v_high`` and duty 0 a constant ``v_low``.
        """
        if isinstance(tick, bool) or not isinstance(tick, int) or tick < 0:
            raise PwmError(f"tick = {tick!r} must be an int >= 0")
        return self.v_high if tick % self._period < self.duty else self.v_low

    def waveform(self, n_ticks: int | None = None) -> Iterator[float]:
        """Yield the output level tick by tick, from tick 0 (forever if ``n_ticks`` is None).

        The duty is read at every tick, as the interrupt reads ``pwm_duty`` when it
        reloads the timer, so a ``set_velocity`` between ticks takes effect.
        """
        tick = 0
        while n_ticks is None or tick < n_ticks:
            yield self.level_at(tick)
            tick += 1

    def __repr__(self) -> str:
        return (
            f"PwmVelocityController(duty={self.duty}, period_ticks={self._period}, "
            f"average_voltage={self.average_voltage:+.4f} V)"
        )
