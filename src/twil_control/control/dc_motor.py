"""Permanent-magnet DC motor + gearbox driving one wheel of qbot (the qbot report's Section 3).

Pure math, numpy only. The report drives each wheel with a ±5 V PWM and assumes the wheel's
speed linear in the voltage; this model is the physics behind that assumption, so that it can
be checked and its limits stated. The model, why the inductance is left out, when speed is
linear in voltage and where the default parameters come from: docs/qbot.md, "The DC motor model".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from twil_control.errors import TwilControlError

from .floats import as_float

__all__ = [
    "DcMotorError",
    "DcMotorParams",
    "motor_current",
    "no_load_speed",
    "stall_torque",
    "steady_state_speed",
    "voltage_for_speed",
    "wheel_torque",
    "motor_torque",
    "holding_voltage",
]


class DcMotorError(TwilControlError, ValueError):
    """An invalid DC motor parameter or input (a ValueError)."""


@dataclass(frozen=True)
class DcMotorParams:
    """DC motor + gearbox parameters, SI units, referred to the wheel (qbot report, Section 3).

    Attributes:
        resistance_ohm: armature winding resistance R (ohm), > 0.
        torque_constant: k_t (N m/A), > 0.
        back_emf_constant: k_e (V s/rad), > 0 (equal to k_t in SI for an ideal motor).
        gear_ratio: N, motor revolutions per wheel revolution, > 0.
        gear_efficiency: eta in (0, 1], multiplies the delivered torque.
        friction_viscous: b (N m s/rad) at the wheel, >= 0.
        max_voltage: supply magnitude (V), > 0; the applied voltage is clipped to +-it.
    """

    resistance_ohm: float = 1.0
    torque_constant: float = 0.0057
    back_emf_constant: float = 0.0057
    gear_ratio: float = 100.0
    gear_efficiency: float = 1.0
    friction_viscous: float = 0.0
    max_voltage: float = 5.0

    def __post_init__(self) -> None:
        rules = (
            ("resistance_ohm", lambda x: x > 0.0, "> 0 (ohm)"),
            ("torque_constant", lambda x: x > 0.0, "> 0 (N m/A)"),
            ("back_emf_constant", lambda x: x > 0.0, "> 0 (V s/rad)"),
            ("gear_ratio", lambda x: x > 0.0, "> 0 (motor turns per wheel turn)"),
            ("gear_efficiency", lambda x: 0.0 < x <= 1.0, "in (0, 1]"),
            ("friction_viscous", lambda x: x >= 0.0, ">= 0 (N m s/rad at the wheel)"),
            ("max_voltage", lambda x: x > 0.0, "> 0 (V)"),
        )
        for name, ok, rule in rules:
            value = getattr(self, name)
            f = as_float(value)
            if not math.isfinite(f) or not ok(f):
                raise DcMotorError(
                    f"DcMotorParams.{name} = {value!r} is invalid: it must be a finite number {rule}"
                )

    @property
    def stall_torque_per_volt(self) -> float:
        """``N eta k_t / R`` (N m/V): wheel torque per volt at zero speed."""
        return self.gear_ratio * self.gear_efficiency * self.torque_constant / self.resistance_ohm

    @property
    def damping(self) -> float:
        """``N^2 eta k_t k_e / R + b`` (N m s/rad): torque lost per rad/s of wheel speed."""
        return self.stall_torque_per_volt * self.back_emf_constant * self.gear_ratio + self.friction_viscous


DEFAULT_PARAMS = DcMotorParams()


def _array(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if not np.all(np.isfinite(a)):
        raise DcMotorError(f"{name} must be finite, got {x!r}")
    return a


def _out(a: np.ndarray):
    return float(a) if np.ndim(a) == 0 else a


def _clip_voltage(voltage, params: DcMotorParams) -> np.ndarray:
    v = _array(voltage, "voltage")
    return np.clip(v, -params.max_voltage, params.max_voltage)


def motor_current(voltage, wheel_speed, params: DcMotorParams = DEFAULT_PARAMS):
    """Armature current ``i = (V - k_e N w) / R`` (A), steady-state electrical (Section 3).

    ``voltage`` is clipped to ``+-params.max_voltage``.
    """
    v = _clip_voltage(voltage, params)
    w = _array(wheel_speed, "wheel_speed")
    return _out((v - params.back_emf_constant * params.gear_ratio * w) / params.resistance_ohm)


@njit(cache=True, nogil=True)
def motor_torque(
    voltage, wheel_speed, stall_torque_per_volt, back_emf_at_wheel, friction_viscous, max_voltage
):
    """``tau = N eta k_t (V - k_e N w) / R - b w`` with ``V`` clipped to ``+-max_voltage``, in the
    constants of :class:`DcMotorParams` (``back_emf_at_wheel = k_e N``): what
    :func:`wheel_torque` computes, compiled (floats or arrays) for the qbot drive's update too."""
    v = np.minimum(np.maximum(voltage, -max_voltage), max_voltage)
    return stall_torque_per_volt * (v - back_emf_at_wheel * wheel_speed) - friction_viscous * wheel_speed


@njit(cache=True, nogil=True)
def holding_voltage(wheel_speed, load_torque, damping, stall_torque_per_volt):
    """``V = (damping w + tau_load) / (N eta k_t / R)``: what :func:`voltage_for_speed` computes."""
    return (damping * wheel_speed + load_torque) / stall_torque_per_volt


def wheel_torque(voltage, wheel_speed, params: DcMotorParams = DEFAULT_PARAMS):
    """Torque delivered to the wheel (N m) at average voltage ``V`` and wheel speed ``w``.

    ``tau = N eta k_t (V - k_e N w) / R - b w`` (the qbot report's Section 3 motor, inductance
    neglected: docs/qbot.md, "The DC motor model"). Positive drives the wheel forward. ``voltage`` is
    clipped to ``+-params.max_voltage``, so ``|tau| <= stall_torque(max_voltage)`` for
    wheel speeds within the no-load range. Scalars or broadcastable arrays.
    """
    v = _array(voltage, "voltage")
    w = _array(wheel_speed, "wheel_speed")
    return _out(
        motor_torque(
            v,
            w,
            params.stall_torque_per_volt,
            params.back_emf_constant * params.gear_ratio,
            params.friction_viscous,
            params.max_voltage,
        )
    )


def stall_torque(voltage, params: DcMotorParams = DEFAULT_PARAMS):
    """Wheel torque at zero speed, ``N eta k_t V / R`` (N m), voltage clipped."""
    return wheel_torque(voltage, 0.0, params)


def steady_state_speed(voltage, load_torque=0.0, params: DcMotorParams = DEFAULT_PARAMS):
    """Wheel speed (rad/s) at which the motor torque equals ``load_torque`` (Section 3).

    ``w_ss = (N eta k_t V / R - tau_load) / (N^2 eta k_t k_e / R + b)``. The load torque
    opposes forward rotation when positive. Affine in ``V``; proportional only at zero
    load (docs/qbot.md). ``voltage`` is clipped to ``+-params.max_voltage``.
    """
    v = _clip_voltage(voltage, params)
    tau_l = _array(load_torque, "load_torque")
    return _out((params.stall_torque_per_volt * v - tau_l) / params.damping)


def no_load_speed(voltage, params: DcMotorParams = DEFAULT_PARAMS):
    """No-load wheel speed (rad/s): ``V / (k_e N)`` for ``b = 0``; linear in ``V``.

    This is the qbot report's Section 3 assumption ("the velocity linearly depends on the
    voltage"), exact for this model at no load, with or without viscous friction.
    """
    return steady_state_speed(voltage, 0.0, params)


def voltage_for_speed(wheel_speed, load_torque=0.0, params: DcMotorParams = DEFAULT_PARAMS):
    """Average voltage that holds ``wheel_speed`` against ``load_torque`` (inverse of
    :func:`steady_state_speed`), NOT clipped: compare with ``params.max_voltage`` to see
    whether the speed is reachable. Divide by ``max_voltage`` for the PWM's normalised
    velocity command (qbot report, Section 3).
    """
    w = _array(wheel_speed, "wheel_speed")
    tau_l = _array(load_torque, "load_torque")
    return _out(holding_voltage(w, tau_l, params.damping, params.stall_torque_per_volt))
