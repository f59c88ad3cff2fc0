"""Wheel odometry (diff_drive_controller's Odometry role) integrating the qbot report's Section 1."""

import math

import pytest

from twil_control.control.diff_odometry import (
    OdometryError,
    WheelOdometry,
    integrate_exact,
    integrate_runge_kutta2,
)
from twil_control.control.skid_steer import wheel_speeds

pytestmark = pytest.mark.kernels

TWIL = (0.075, 0.322)
QBOT = (0.055, 0.36)


def drive(odom, w_left, w_right, duration, dt, t0=0.0):
    """Feed exact wheel angles for constant wheel speeds (rad/s)."""
    n = round(duration / dt)
    for k in range(n + 1):
        t = t0 + k * dt
        odom.update(w_left * t, w_right * t, t)


@pytest.mark.parametrize("robot", [TWIL, QBOT], ids=["twil", "qbot"])
@pytest.mark.parametrize("dt", [0.001, 0.05])
def test_circle_of_known_radius_gives_the_exact_pose_to_1e_6(robot, dt):
    r, b = robot
    radius, v = 1.5, 0.4
    w = v / radius
    wl, wr = wheel_speeds(v, w, r, b / 2)
    odom = WheelOdometry(r, b)
    duration = 20.0  # 5.33 rad: most of a lap
    drive(odom, wl, wr, duration, dt)
    th = w * duration
    assert odom.heading == pytest.approx(th, abs=1e-6)
    assert odom.x == pytest.approx(radius * math.sin(th), abs=1e-6)
    assert odom.y == pytest.approx(radius * (1.0 - math.cos(th)), abs=1e-6)
    assert odom.linear == pytest.approx(v, abs=1e-6)
    assert odom.angular == pytest.approx(w, abs=1e-6)


def test_full_laps_return_to_the_start_with_continuous_heading():
    r, b = QBOT
    wl, wr = wheel_speeds(0.3, 0.6, r, b / 2)  # radius 0.5 m
    odom = WheelOdometry(r, b)
    duration = 2 * (2 * math.pi / 0.6)  # two laps
    drive(odom, wl, wr, duration, duration / 4000)
    assert (odom.x, odom.y) == pytest.approx((0.0, 0.0), abs=1e-6)
    assert odom.heading == pytest.approx(4 * math.pi, abs=1e-6)
    assert odom.yaw == pytest.approx(0.0, abs=1e-6)


def test_straight_line_from_a_reset_pose():
    r, b = TWIL
    odom = WheelOdometry(r, b)
    odom.reset(1.0, -2.0, math.pi / 4)
    drive(odom, 4.0, 4.0, 2.5, 0.01)  # 4 rad/s * 0.075 m = 0.3 m/s for 2.5 s = 0.75 m
    d = 0.75
    assert odom.x == pytest.approx(1.0 + d / math.sqrt(2), abs=1e-9)
    assert odom.y == pytest.approx(-2.0 + d / math.sqrt(2), abs=1e-9)
    assert odom.heading == pytest.approx(math.pi / 4, abs=1e-12)
    assert odom.twist == pytest.approx((0.3, 0.0), abs=1e-9)


def test_pure_rotation_keeps_the_position():
    r, b = QBOT
    odom = WheelOdometry(r, b)
    drive(odom, -3.0, 3.0, 1.0, 0.01)
    assert (odom.x, odom.y) == pytest.approx((0.0, 0.0), abs=1e-12)
    assert odom.heading == pytest.approx(2 * r * 3.0 / b, abs=1e-12)  # 0.9167 rad
    assert odom.linear == pytest.approx(0.0, abs=1e-12)
    assert odom.angular == pytest.approx(2 * r * 3.0 / b, abs=1e-9)


def test_first_update_initialises_without_jumping_by_the_absolute_wheel_angles():
    odom = WheelOdometry(*TWIL)
    assert odom.update(123.0, -45.0, 10.0) is False
    assert odom.pose == (0.0, 0.0, 0.0) and odom.initialized
    assert odom.update(124.0, -44.0, 10.1) is True
    assert odom.x == pytest.approx(0.075, abs=1e-12)


def test_velocity_is_a_rolling_mean_over_the_window():
    odom = WheelOdometry(1.0, 1.0, velocity_rolling_window_size=4)
    odom.update(0.0, 0.0, 0.0)
    angle = 0.0
    for k, speed in enumerate([1.0, 1.0, 1.0, 1.0, 5.0], start=1):
        angle += speed * 0.1
        odom.update(angle, angle, 0.1 * k)
    assert odom.linear == pytest.approx((1.0 + 1.0 + 1.0 + 5.0) / 4, abs=1e-9)


def test_updates_closer_than_0_1_ms_move_the_pose_but_not_the_velocity():
    odom = WheelOdometry(1.0, 1.0)
    odom.update(0.0, 0.0, 0.0)
    odom.update(0.1, 0.1, 0.1)
    assert odom.update(0.2, 0.2, 0.10005) is False
    assert odom.x == pytest.approx(0.2, abs=1e-12)
    assert odom.linear == pytest.approx(1.0, abs=1e-12)


def test_exact_and_rk2_steps_agree_for_small_turns_and_switch_at_1e_6():
    exact = integrate_exact(0.0, 0.0, 0.3, 0.01, 1e-3)
    rk2 = integrate_runge_kutta2(0.0, 0.0, 0.3, 0.01, 1e-3)
    assert exact == pytest.approx(rk2, abs=1e-9)
    tiny = (0.0, 0.0, 0.3, 0.01, 1e-7)
    assert integrate_exact(*tiny) == integrate_runge_kutta2(*tiny)


def test_open_loop_update_integrates_commanded_velocities():
    odom = WheelOdometry(*QBOT)
    odom.update_open_loop(0.5, 0.0, 0.0)
    for k in range(1, 11):
        odom.update_open_loop(0.5, 0.0, 0.1 * k)
    assert odom.x == pytest.approx(0.5, abs=1e-12) and odom.linear == 0.5


def test_invalid_inputs_are_refused():
    with pytest.raises(ValueError, match="wheel_radius"):
        WheelOdometry(0.0, 0.3)
    with pytest.raises(ValueError, match="wheel_separation"):
        WheelOdometry(0.05, math.nan)
    with pytest.raises(ValueError, match="velocity_rolling_window_size"):
        WheelOdometry(0.05, 0.3, velocity_rolling_window_size=0)
    odom = WheelOdometry(*QBOT)
    odom.update(0.0, 0.0, 1.0)
    with pytest.raises(OdometryError, match="left_pos"):
        odom.update(math.nan, 0.0, 1.1)
    with pytest.raises(OdometryError, match="before the previous update"):
        odom.update(0.0, 0.0, 0.5)
