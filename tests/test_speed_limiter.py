"""diff_drive_controller's SpeedLimiter role, twil_control.control.speed_limiter."""

import math

import pytest

from twil_control.control.speed_limiter import SpeedLimiter, SpeedLimiterError

pytestmark = pytest.mark.kernels


def limiter(**kw):
    base = dict(
        has_velocity_limits=True,
        has_acceleration_limits=True,
        min_velocity=-1.0,
        max_velocity=1.0,
        min_acceleration=-2.0,
        max_acceleration=2.0,
    )
    base.update(kw)
    return SpeedLimiter(**base)


def test_velocity_is_clamped_to_its_limits():
    lim = limiter(has_acceleration_limits=False)
    assert lim.limit(2.0, 0.0, 0.01) == 1.0
    assert lim.limit(-3.0, 0.0, 0.01) == -1.0
    assert lim.limit(0.4, 0.0, 0.01) == 0.4


def test_acceleration_limits_the_change_per_step():
    lim = limiter()
    assert lim.limit(1.0, 0.0, 0.1) == pytest.approx(0.2, abs=1e-15)
    assert lim.limit(-1.0, 1.0, 0.1) == pytest.approx(0.8, abs=1e-15)
    assert lim.limit(0.15, 0.0, 0.1) == 0.15  # within the limit: unchanged


def test_velocity_limit_applies_after_acceleration_limit():
    assert limiter().limit(5.0, 0.95, 0.1) == 1.0  # 0.95 + 0.2 = 1.15, then clamped


def test_min_limits_default_to_minus_max_as_ros_parameters_do():
    lim = SpeedLimiter(True, True, max_velocity=0.5, max_acceleration=2.5)
    assert (lim.min_velocity, lim.min_acceleration) == (-0.5, -2.5)
    assert lim.limit(-9.0, -0.45, 0.01) == pytest.approx(-0.475, abs=1e-15)


def test_asymmetric_limits():
    lim = limiter(min_velocity=-0.2, min_acceleration=-0.5)
    assert lim.limit(-1.0, 0.0, 0.1) == pytest.approx(-0.05, abs=1e-15)
    assert lim.limit(-1.0, -0.19, 1.0) == -0.2


def test_disabled_limits_pass_the_command_through():
    lim = SpeedLimiter(False, False, -1.0, 1.0, -2.0, 2.0)
    assert lim.limit(7.5, -3.0, 0.001) == 7.5


def test_stateful_ramp_reaches_the_target_at_the_acceleration_limit():
    lim = limiter(max_acceleration=1.0, min_acceleration=-1.0)
    out = [lim.step(1.0, 0.1) for _ in range(12)]
    assert out[0] == pytest.approx(0.1, abs=1e-15)
    assert out[9] == pytest.approx(1.0, abs=1e-12)
    assert out[11] == 1.0
    lim.reset()
    assert lim.step(1.0, 0.1) == pytest.approx(0.1, abs=1e-15)


def test_jerk_limit_bounds_the_change_of_acceleration():
    lim = limiter(
        has_acceleration_limits=False,
        has_jerk_limits=True,
        max_jerk=10.0,
        max_velocity=5.0,
        min_velocity=-5.0,
    )
    dt = 0.1
    # From rest, the first step may change the acceleration by at most j dt = 1 m/s^2,
    # i.e. the velocity by j dt^2 = 0.1 m/s.
    assert lim.limit(1.0, 0.0, dt, 0.0) == pytest.approx(0.1, abs=1e-15)
    # With a previous step of 0.1, the next may be at most 0.1 + 0.1 = 0.2.
    assert lim.limit(1.0, 0.1, dt, 0.0) == pytest.approx(0.3, abs=1e-15)
    seq = [lim.step(3.0, dt) for _ in range(5)]
    steps = [b - a for a, b in zip([0.0] + seq, seq)]
    assert steps == pytest.approx([0.1, 0.2, 0.3, 0.4, 0.5], abs=1e-12)


def test_zero_dt_allows_no_change_even_with_infinite_limits():
    lim = limiter(max_acceleration=math.inf, min_acceleration=-math.inf)
    assert lim.limit(0.9, 0.3, 0.0) == 0.3


def test_ros_scale_factor():
    lim = limiter()
    v = 1.0
    assert lim.factor(v, lim.limit(v, 0.0, 0.1)) == pytest.approx(0.2)
    assert lim.factor(0.0, 0.0) == 1.0


@pytest.mark.parametrize(
    "args", [(math.nan, 0.0, 0.1), (0.1, math.nan, 0.1), (0.1, 0.0, math.nan), (math.inf, 0.0, 0.1)]
)
def test_nan_or_inf_input_raises_value_error(args):
    with pytest.raises(ValueError, match="not a finite number"):
        limiter().limit(*args)


def test_negative_dt_and_bad_limits_are_refused():
    with pytest.raises(SpeedLimiterError, match="dt"):
        limiter().limit(0.1, 0.0, -0.01)
    with pytest.raises(ValueError, match="min_velocity"):
        limiter(min_velocity=2.0)
    with pytest.raises(ValueError, match="max_acceleration"):
        limiter(max_acceleration=math.nan)
