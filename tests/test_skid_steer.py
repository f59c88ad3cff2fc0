"""Skid-steer kinematics of qbot (the qbot report's Sections 1 and 2), twil_control.control.skid_steer."""

import math

import numpy as np
import pytest

from twil_control.control.skid_steer import (
    SkidSteerError,
    body_velocity,
    configuration_rate,
    forward_matrix,
    motor_matrix,
    report_printed_motor_matrix,
    wheel_speeds,
)

R = 0.055  # qbot wheel radius (m)
C = 0.18  # qbot half track (m): wheels at y = +-0.18, track 2c = 0.36


def test_wheel_speeds_then_body_velocity_returns_the_command_to_1e_12():
    rng = np.random.default_rng(1)
    v = rng.uniform(-1.0, 1.0, 1000)
    w = rng.uniform(-3.0, 3.0, 1000)
    wl, wr = wheel_speeds(v, w, R, C)
    v2, w2 = body_velocity(wl, wr, R, C)
    assert np.max(np.abs(v2 - v)) < 1e-12
    assert np.max(np.abs(w2 - w)) < 1e-12


def test_scalar_round_trip_gives_python_floats():
    wl, wr = wheel_speeds(0.3, -0.7, R, C)
    assert isinstance(wl, float) and isinstance(wr, float)
    v, w = body_velocity(wl, wr, R, C)
    assert v == pytest.approx(0.3, abs=1e-12)
    assert w == pytest.approx(-0.7, abs=1e-12)


def test_straight_line_spins_both_wheels_at_v_over_r():
    wl, wr = wheel_speeds(0.5, 0.0, R, C)
    assert wl == pytest.approx(0.5 / R, abs=1e-12)
    assert wr == pytest.approx(0.5 / R, abs=1e-12)
    assert wl == pytest.approx(9.0909090909, abs=1e-9)


def test_turn_in_place_counter_clockwise_spins_right_wheel_forward():
    # REP 103: w > 0 turns left (counter-clockwise), so the right wheel goes forward.
    wl, wr = wheel_speeds(0.0, 2.0, R, C)
    assert wr == pytest.approx(C * 2.0 / R, abs=1e-12)  # 6.5454... rad/s
    assert wl == pytest.approx(-wr, abs=1e-12)
    v, w = body_velocity(wl, wr, R, C)
    assert v == pytest.approx(0.0, abs=1e-12)
    assert w == pytest.approx(2.0, abs=1e-12)


def test_motor_matrix_is_the_inverse_of_the_section_1_forward_map():
    np.testing.assert_allclose(motor_matrix(R, C) @ forward_matrix(R, C), np.eye(2), atol=1e-12)
    np.testing.assert_allclose(forward_matrix(R, C) @ motor_matrix(R, C), np.eye(2), atol=1e-12)
    np.testing.assert_allclose(motor_matrix(R, C), np.array([[1, -C], [1, C]]) / R, atol=0)


def test_seed_printed_section_2_matrix_inverts_the_yaw_rate():
    # The qbot report prints [w_L, w_R] = (1/r) [[1, c], [1, -c]] [v, w]. Fed back through its own
    # Section 1 forward model, that reproduces v but flips the sign of w: a left-turn
    # command would turn the robot right.
    printed = report_printed_motor_matrix(R, C)
    np.testing.assert_allclose(forward_matrix(R, C) @ printed, np.diag([1.0, -1.0]), atol=1e-12)
    wl, wr = printed @ np.array([0.2, 1.0])
    v, w = body_velocity(wl, wr, R, C)
    assert v == pytest.approx(0.2, abs=1e-12)
    assert w == pytest.approx(-1.0, abs=1e-12)  # inverted
    assert wheel_speeds(0.2, 1.0, R, C)[1] > wheel_speeds(0.2, 1.0, R, C)[0]  # corrected


def test_configuration_rate_is_s_of_q_times_eta():
    xd, yd, thd = configuration_rate(0.0, 0.5, 0.3)
    assert (xd, yd, thd) == pytest.approx((0.5, 0.0, 0.3), abs=1e-15)
    xd, yd, thd = configuration_rate(math.pi / 2, 0.5, -0.3)
    assert (xd, yd, thd) == pytest.approx((0.0, 0.5, -0.3), abs=1e-15)
    th = np.linspace(-math.pi, math.pi, 7)
    xd, yd, thd = configuration_rate(th, 2.0, 1.0)
    np.testing.assert_allclose(np.hypot(xd, yd), 2.0, atol=1e-12)
    np.testing.assert_allclose(thd, np.ones(7), atol=0)


@pytest.mark.parametrize(
    "r, c, name",
    [
        (0.0, C, "r"),
        (-0.055, C, "r"),
        (float("nan"), C, "r"),
        (R, 0.0, "c"),
        (R, -0.18, "c"),
        (R, float("inf"), "c"),
    ],
)
def test_invalid_geometry_raises_value_error_naming_the_parameter(r, c, name):
    with pytest.raises(ValueError, match=rf"^{name} = "):
        wheel_speeds(0.1, 0.1, r, c)
    with pytest.raises(SkidSteerError, match=rf"^{name} = "):
        body_velocity(1.0, 1.0, r, c)
