"""control_toolbox::Pid replica (twil_control.control.pid)."""

from __future__ import annotations

import math

import pytest

from twil_control.control.pid import Pid


def test_proportional_integral_derivative_terms():
    pid = Pid(p=2.0, i=0.5, d=0.1, i_clamp=10.0)
    # p*e + i*(dt*e) + d*e_dot = 2*1 + 0.5*0.01 + 0.1*3
    assert pid.compute_command(1.0, 3.0, 0.01) == pytest.approx(2.0 + 0.005 + 0.3)
    assert pid.compute_command(1.0, 0.0, 0.01) == pytest.approx(2.0 + 0.5 * 0.02)


def test_integral_term_is_clamped_but_integrates_on_without_antiwindup():
    pid = Pid(p=0.0, i=1.0, i_clamp=0.5)
    for _ in range(100):
        out = pid.compute_command(1.0, 0.0, 0.1)
    assert out == pytest.approx(0.5)
    assert pid.i_error == pytest.approx(10.0)  # windup, as control_toolbox without antiwindup
    for _ in range(5):
        out = pid.compute_command(-1.0, 0.0, 0.1)
    assert out == pytest.approx(0.5)  # still saturated: the wound-up integral takes 95 steps to unwind


def test_antiwindup_clamps_the_integral_itself():
    pid = Pid(p=0.0, i=2.0, i_clamp=0.5, antiwindup=True)
    for _ in range(100):
        pid.compute_command(1.0, 0.0, 0.1)
    assert pid.i_error == pytest.approx(0.25)  # i_max / |i|
    assert pid.compute_command(-1.0, 0.0, 0.1) == pytest.approx(2.0 * 0.15)  # unwinds at once


def test_separate_clamp_limits():
    pid = Pid(i=1.0, i_min=-0.2, i_max=0.7)
    assert [pid.compute_command(100.0, 0.0, 1.0) for _ in range(2)][-1] == pytest.approx(0.7)
    pid.reset()
    assert pid.compute_command(-100.0, 0.0, 1.0) == pytest.approx(-0.2)
    with pytest.raises(ValueError):
        Pid(i_min=1.0, i_max=0.0)


def test_error_rate_from_finite_difference():
    pid = Pid(p=0.0, d=1.0)
    assert pid.compute_command_from_error(0.5, 0.1) == pytest.approx(5.0)  # (0.5 - 0) / 0.1
    assert pid.compute_command_from_error(0.6, 0.1) == pytest.approx(1.0)
    assert pid.computeCommand(0.6, 0.1) == pytest.approx(0.0)  # two-argument overload
    assert pid.computeCommand(0.6, 2.0, 0.1) == pytest.approx(2.0)  # three-argument overload


@pytest.mark.parametrize(
    "error, error_dot, dt", [(math.nan, 0.0, 0.1), (1.0, math.inf, 0.1), (1.0, 0.0, 0.0)]
)
def test_invalid_inputs_return_zero_and_leave_state(error, error_dot, dt):
    pid = Pid(p=1.0, i=1.0, i_clamp=10.0)
    pid.compute_command(1.0, 0.0, 0.1)
    before = pid.i_error
    assert pid.compute_command(error, error_dot, dt) == 0.0
    assert pid.i_error == before


def test_reset_clears_integral_and_memory():
    pid = Pid(p=1.0, i=1.0, d=1.0, i_clamp=10.0)
    pid.compute_command_from_error(1.0, 0.1)
    pid.reset()
    assert (pid.i_error, pid.p_error_last) == (0.0, 0.0)
