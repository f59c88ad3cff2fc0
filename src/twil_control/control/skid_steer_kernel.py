"""qbot's PWM drive for one 1 kHz update: the drive chain's equations composed and compiled (numba).

Each step is the one implementation of its equation that the Python API calls too: the speed
limits, skid_steer.motor_commands, the DC motor and the PWM (docs/qbot.md). One compiled call,
because most of the Python pieces' cost is validating scalars and building tiny arrays
(bench/qbot_bench.py). The arrays' layout is in `pwm_drive`'s docstring.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .dc_motor import holding_voltage, motor_torque
from .pwm import average_voltage, duty_of
from .skid_steer import motor_commands
from .speed_limiter import limited

__all__ = ["OUT_SIZE", "motor_row", "pwm_drive"]

OUT_SIZE = 6


def motor_row(params) -> np.ndarray:
    """dc_motor.DcMotorParams as the `motor` array."""
    return np.array(
        [
            params.stall_torque_per_volt,
            params.damping,
            params.back_emf_constant * params.gear_ratio,
            params.friction_viscous,
            params.max_voltage,
        ]
    )


@njit(cache=True, nogil=True)
def _limit(v, row, hist, dt):
    """One axis's limited command, its history (v0, v1) moved on."""
    v = limited(v, hist[0], hist[1], dt, row)
    hist[1] = hist[0]
    hist[0] = v
    return v


@njit(cache=True, nogil=True)
def pwm_drive(
    v, w, dt, limits, history, r, c, motor, period, v_high, v_low, side, joints, velocity, effort, out
):
    """The limited command, the wheel targets, each side's PWM duty and average voltage (the
    qbot report's open loop: the voltage that holds the target speed at no load, as a velocity
    command in [-1, 1]), and each joint's motor torque at its measured speed, written to
    effort[joints]. The controller preallocates the arrays once:

    - limits (2, 9): per axis (linear x, angular z) the SpeedLimiter's `row` (LIMIT_FIELDS);
    - history (2, 2): per axis the last two limited commands (v0, v1), updated in place;
    - motor (5): stall torque per volt N eta k_t / R, damping N^2 eta k_t k_e / R + b, back-EMF
      at the wheel k_e N, viscous friction b, max_voltage (`motor_row`);
    - side: 0 (left) or 1 (right) for each driven joint; joints: its index in velocity/effort;
    - out (6): limited v, limited w, left and right wheel targets (rad/s), left and right duty.
    """
    v = _limit(v, limits[0], history[0], dt)
    w = _limit(w, limits[1], history[1], dt)
    left, right = motor_commands(v, w, r, c)
    stall_per_volt, damping, back_emf, friction, max_voltage = (
        motor[0],
        motor[1],
        motor[2],
        motor[3],
        motor[4],
    )
    average = np.empty(2)
    for s, target in ((0, left), (1, right)):
        duty = duty_of(holding_voltage(target, 0.0, damping, stall_per_volt) / max_voltage, period)
        out[4 + s] = duty
        average[s] = average_voltage(duty, period, v_high, v_low)
    for k in range(joints.shape[0]):
        effort[joints[k]] = motor_torque(
            average[side[k]], velocity[joints[k]], stall_per_volt, back_emf, friction, max_voltage
        )
    out[0], out[1], out[2], out[3] = v, w, left, right
