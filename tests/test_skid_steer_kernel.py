"""control/skid_steer_kernel.py (qbot's compiled PWM drive) composes the drive chain's
equations as the Python API does step by step: SpeedLimiter.step, skid_steer.wheel_speeds,
dc_motor.voltage_for_speed / wheel_torque and PwmVelocityController (the API's checks and state
around the same functions)."""

from __future__ import annotations

import numpy as np
import pytest

from twil_control.control import dc_motor, skid_steer, skid_steer_kernel
from twil_control.control.pwm import PwmVelocityController
from twil_control.control.speed_limiter import SpeedLimiter

pytestmark = pytest.mark.kernels

R, C = 0.055, 0.18


def limiters(jerk: bool):
    lin = SpeedLimiter(True, True, None, 0.45, None, 1.0, has_jerk_limits=jerk, max_jerk=200.0)
    ang = SpeedLimiter(
        True, True, -2.0, 2.0, -3.2, 3.2, has_jerk_limits=jerk, min_jerk=-500.0, max_jerk=400.0
    )
    return lin, ang


@pytest.mark.parametrize("jerk", [False, True])
@pytest.mark.parametrize(
    "motor",
    [
        dc_motor.DcMotorParams(),
        dc_motor.DcMotorParams(gear_efficiency=0.6, friction_viscous=0.01, max_voltage=6.0),
    ],
)
def test_pwm_drive_matches_the_python_pieces_over_2000_steps(jerk, motor):
    rng = np.random.default_rng(3)
    lin, ang = limiters(jerk)
    ref_lin, ref_ang = limiters(jerk)
    pwm = (
        PwmVelocityController(motor.max_voltage, -motor.max_voltage),
        PwmVelocityController(motor.max_voltage, -motor.max_voltage),
    )
    limits = np.array([lin.row, ang.row])
    history = np.zeros((2, 2))
    side = np.array([0, 0, 1, 1])
    joints = np.array([5, 2, 0, 3])  # scattered in the hardware's arrays
    velocity, effort, out = np.zeros(6), np.zeros(6), np.zeros(skid_steer_kernel.OUT_SIZE)
    saturated = 0
    for k in range(2000):
        if k % 400 == 0:  # a new command now and then: within and beyond the limits
            v, w = rng.uniform(-0.8, 0.8), rng.uniform(-3.0, 3.0)
        dt = 0.0 if k % 97 == 0 else 0.001  # dt = 0 happens (inf * 0 = 0)
        velocity[:] = rng.uniform(-12.0, 12.0, 6)
        skid_steer_kernel.pwm_drive(
            v,
            w,
            dt,
            limits,
            history,
            R,
            C,
            skid_steer_kernel.motor_row(motor),
            pwm[0].period_ticks,
            pwm[0].v_high,
            pwm[0].v_low,
            side,
            joints,
            velocity,
            effort,
            out,
        )
        # the reference, piece by piece
        lv, lw = ref_lin.step(v, dt), ref_ang.step(w, dt)
        targets = skid_steer.wheel_speeds(lv, lw, R, C)
        volts = dc_motor.voltage_for_speed(np.array(targets), 0.0, motor)
        for s in (0, 1):
            pwm[s].set_velocity(float(volts[s]) / motor.max_voltage)
        saturated += np.abs(volts).max() > motor.max_voltage
        average = np.array([pwm[s].average_voltage for s in side])
        tau = dc_motor.wheel_torque(average, velocity[joints], motor)
        assert out[:4] == pytest.approx([lv, lw, *targets], rel=1e-12, abs=1e-12)
        assert (int(out[4]), int(out[5])) == (pwm[0].duty, pwm[1].duty)
        assert effort[joints] == pytest.approx(tau, rel=1e-12, abs=1e-12)
    assert saturated > 0  # the PWM's saturation was exercised
