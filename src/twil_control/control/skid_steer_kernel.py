"""qbot's PWM drive for one 1 kHz update, compiled (numba).

The reference implementation is the pure-Python one the controller is built from:
speed_limiter.SpeedLimiter (diff_drive_controller's limits: jerk, then acceleration, then
velocity), skid_steer.wheel_speeds (seed Section 2), dc_motor.voltage_for_speed and
dc_motor.wheel_torque (Section 3's motor) and pwm.PwmVelocityController (Listing 1,
corrected: 8-bit duty, average voltage). Called one by one they cost about 180 us per update,
most of it validating scalars and building tiny arrays (bench/qbot_bench.py), which made the
drive, not the plant, the bound on qbot's real-time factor. tests/test_skid_steer_kernel.py
checks this against the reference, step by step, over random command sequences.

Arrays (the controller preallocates them once):
- limits (2, 9): per axis (linear x, angular z) has_velocity_limits, min_velocity,
  max_velocity, has_acceleration_limits, min_acceleration, max_acceleration,
  has_jerk_limits, min_jerk, max_jerk (flags as 0.0 / 1.0);
- history (2, 2): per axis the last two limited commands (v0, v1), updated in place;
- motor (5): stall torque per volt N eta k_t / R, damping N^2 eta k_t k_e / R + b, back-EMF
  at the wheel k_e N, viscous friction b, max_voltage;
- side: 0 (left) or 1 (right) for each driven joint, joints: its index in velocity/effort;
- out (6): limited v, limited w, left and right wheel targets (rad/s), left and right duty.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["LIMIT_FIELDS", "OUT_SIZE", "limits_row", "motor_row", "pwm_drive"]

LIMIT_FIELDS = ("has_velocity_limits", "min_velocity", "max_velocity", "has_acceleration_limits",
                "min_acceleration", "max_acceleration", "has_jerk_limits", "min_jerk", "max_jerk")
OUT_SIZE = 6


def limits_row(limiter) -> np.ndarray:
    """A SpeedLimiter's limits as one row of `limits` (LIMIT_FIELDS order)."""
    return np.array([float(getattr(limiter, name)) for name in LIMIT_FIELDS])


def motor_row(params) -> np.ndarray:
    """dc_motor.DcMotorParams as the `motor` array."""
    return np.array([params.stall_torque_per_volt, params.damping,
                     params.back_emf_constant * params.gear_ratio, params.friction_viscous,
                     params.max_voltage])


@njit(cache=True, nogil=True)
def _bounded(x, lo, hi):
    return min(max(lo, x), hi)


@njit(cache=True, nogil=True)
def _times(limit, dt):
    # limit * dt with inf * 0 = 0: no change is possible in zero time
    return 0.0 if dt == 0.0 else limit * dt


@njit(cache=True, nogil=True)
def _limited(v, lim, hist, dt):
    """One axis of diff_drive_controller's limiter, history updated (SpeedLimiter.step)."""
    v0, v1 = hist[0], hist[1]
    if lim[6] != 0.0:  # jerk: bound the change of the velocity step
        dv0 = v0 - v1
        dt2 = dt * dt
        v = v0 + dv0 + _bounded((v - v0) - dv0, _times(lim[7], dt2), _times(lim[8], dt2))
    if lim[3] != 0.0:  # acceleration
        v = v0 + _bounded(v - v0, _times(lim[4], dt), _times(lim[5], dt))
    if lim[0] != 0.0:  # velocity
        v = _bounded(v, lim[1], lim[2])
    hist[1] = v0
    hist[0] = v
    return v


@njit(cache=True, nogil=True)
def _duty(volts, max_voltage, period):
    # Listing 1 corrected: saturate the normalised velocity, then P/2 + round half away
    vel = min(1.0, max(-1.0, volts / max_voltage))
    half = period // 2
    x = vel * half
    n = math.floor(abs(x) + 0.5)
    duty = half + (int(n) if x >= 0.0 else -int(n))
    return min(period, max(0, duty))


@njit(cache=True, nogil=True)
def pwm_drive(v, w, dt, limits, history, r, c, motor, period, v_high, v_low, side, joints,
              velocity, effort, out):
    """The limited command, the wheel targets, each side's PWM duty and average voltage, and
    each joint's motor torque at its measured speed, written to effort[joints]."""
    v = _limited(v, limits[0], history[0], dt)
    w = _limited(w, limits[1], history[1], dt)
    targets = ((v - c * w) / r, (v + c * w) / r)
    stall_per_volt, damping, back_emf, friction, max_voltage = motor[0], motor[1], motor[2], motor[3], motor[4]
    average = np.empty(2)
    for s in range(2):
        duty = _duty(damping * targets[s] / stall_per_volt, max_voltage, period)
        out[4 + s] = duty
        average[s] = (duty * v_high + (period - duty) * v_low) / period
    for k in range(joints.shape[0]):
        speed = velocity[joints[k]]
        volts = _bounded(average[side[k]], -max_voltage, max_voltage)
        effort[joints[k]] = stall_per_volt * (volts - back_emf * speed) - friction * speed
    out[0], out[1], out[2], out[3] = v, w, targets[0], targets[1]
