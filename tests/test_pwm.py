"""PWM velocity controller of qbot (the qbot report's Section 3, Listing 1, without its defects)."""

import math

import numpy as np
import pytest

from twil_control.control.pwm import (
    DEFAULT_PERIOD_TICKS,
    PwmError,
    PwmVelocityController,
    duty_to_average_voltage,
    velocity_to_duty,
)

pytestmark = pytest.mark.kernels

STEP = 10.0 / 254  # one duty step in volts: 0.03937 V


@pytest.mark.parametrize(
    "vel, duty, voltage",
    [
        (-1.5, 0, -5.0),  # saturates (Listing 1 left 1.5 uncapped)
        (-1.0, 0, -5.0),
        (-0.5, 63, -640.0 / 254),  # (63*5 - 191*5)/254 = -2.519685 V
        (0.0, 127, 0.0),  # 127 high + 127 low: exactly 0 V
        (0.5, 191, 640.0 / 254),  # +2.519685 V
        (1.0, 254, 5.0),  # full forward, no wrap to 0
        (1.5, 254, 5.0),
    ],
)
def test_duty_and_average_voltage_at_reference_commands(vel, duty, voltage):
    pwm = PwmVelocityController()
    assert pwm.set_velocity(vel) == duty
    assert pwm.duty == duty and type(pwm.duty) is int and 0 <= pwm.duty <= 255
    assert pwm.high_ticks == duty and pwm.low_ticks == 254 - duty and pwm.period_ticks == 254
    assert pwm.average_voltage == pytest.approx(voltage, abs=1e-12)


def test_zero_velocity_is_exactly_zero_volts():
    pwm = PwmVelocityController()
    assert pwm.average_voltage == 0.0  # a new controller outputs 0 V
    pwm.set_velocity(0.7)
    pwm.set_velocity(0.0)
    assert pwm.average_voltage == 0.0
    assert pwm.high_ticks == pwm.low_ticks == 127


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf"), "fast", None])
def test_nan_and_inf_are_refused_naming_the_value_and_the_duty_is_kept(bad):
    pwm = PwmVelocityController()
    pwm.set_velocity(0.5)
    with pytest.raises(ValueError, match=repr(bad).replace("(", r"\(").replace(")", r"\)")):
        pwm.set_velocity(bad)
    assert pwm.duty == 191 and pwm.velocity == 0.5
    with pytest.raises(PwmError):
        velocity_to_duty(bad)


def test_quantisation_error_is_at_most_half_a_duty_step_over_a_fine_sweep():
    pwm = PwmVelocityController()
    worst = 0.0
    for vel in np.linspace(-1.3, 1.3, 26001):
        pwm.set_velocity(vel)
        ideal = 5.0 * min(1.0, max(-1.0, vel))
        worst = max(worst, abs(pwm.average_voltage - ideal))
    assert worst <= 0.5 * STEP + 1e-12  # 0.0197 V, well within the one-step (0.0394 V) bound
    assert worst > 0.49 * STEP  # the bound is tight


def test_duty_is_monotonic_and_antisymmetric_in_velocity():
    vels = np.linspace(-1.2, 1.2, 4801)
    duties = [velocity_to_duty(v) for v in vels]
    assert all(b >= a for a, b in zip(duties, duties[1:]))
    assert set(duties) == set(range(255))  # every duty 0..254 is reachable, 255 never
    for v in vels:
        assert velocity_to_duty(-v) == 254 - velocity_to_duty(v)


@pytest.mark.parametrize("vel", [-1.0, -0.5, -0.013, 0.0, 0.004, 0.25, 0.5, 0.999, 1.0])
def test_waveform_average_over_one_period_equals_average_voltage_exactly(vel):
    pwm = PwmVelocityController()
    pwm.set_velocity(vel)
    levels = list(pwm.waveform(pwm.period_ticks))
    assert len(levels) == 254 and set(levels) <= {5.0, -5.0}
    assert levels.count(5.0) == pwm.high_ticks and levels.count(-5.0) == pwm.low_ticks
    assert sum(levels) / pwm.period_ticks == pwm.average_voltage  # exact, not approx
    # The high phase comes first and the waveform repeats every period.
    assert levels == [5.0] * pwm.high_ticks + [-5.0] * pwm.low_ticks
    assert [pwm.level_at(t + 3 * 254) for t in range(254)] == levels


def test_full_scale_is_a_constant_level_with_no_empty_phase_toggle():
    pwm = PwmVelocityController()
    pwm.set_velocity(1.0)
    assert set(pwm.waveform(1000)) == {5.0}
    pwm.set_velocity(-1.0)
    assert set(pwm.waveform(1000)) == {-5.0}


def test_listing_1_defects_are_not_reproduced():
    # Listing 1 as the 8051 ran it: integer abs() on a float (so 1.5 is not capped) and a
    # duty scaled to 256 stored in an unsigned char (so 256 wraps to 0), period 255.
    def listing1_duty(vel):
        if vel > 1.0 or vel < -1.0:
            vel = vel / abs(int(vel))
        return int((vel + 1.0) * 128.0) % 256

    assert listing1_duty(1.0) == 0  # full forward became full reverse
    assert listing1_duty(1.5) == 64  # not capped, then wrapped
    assert (listing1_duty(0.0) * 5.0 - (255 - listing1_duty(0.0)) * 5.0) / 255 == pytest.approx(
        0.0196, abs=1e-4
    )  # zero velocity was +0.0196 V
    assert velocity_to_duty(1.0) == 254 and velocity_to_duty(1.5) == 254
    assert duty_to_average_voltage(velocity_to_duty(0.0)) == 0.0


def test_other_even_periods_and_levels():
    pwm = PwmVelocityController(v_high=12.0, v_low=-12.0, period_ticks=200)
    assert pwm.set_velocity(0.0) == 100 and pwm.average_voltage == 0.0
    assert pwm.set_velocity(0.5) == 150 and pwm.average_voltage == pytest.approx(6.0, abs=1e-12)
    assert pwm.voltage_step == pytest.approx(0.12)
    unipolar = PwmVelocityController(v_high=5.0, v_low=0.0)
    unipolar.set_velocity(0.0)
    assert unipolar.average_voltage == 2.5 == unipolar.ideal_voltage


@pytest.mark.parametrize("period", [255, 253, 256, 0, 1, 2.0, True])
def test_invalid_period_is_refused(period):
    with pytest.raises(ValueError, match="period_ticks"):
        PwmVelocityController(period_ticks=period)


def test_invalid_levels_and_ticks_are_refused():
    with pytest.raises(ValueError, match="v_low"):
        PwmVelocityController(v_high=-5.0, v_low=5.0)
    with pytest.raises(ValueError, match="v_high"):
        PwmVelocityController(v_high=math.nan)
    with pytest.raises(ValueError, match="tick"):
        PwmVelocityController().level_at(-1)
    assert DEFAULT_PERIOD_TICKS == 254
