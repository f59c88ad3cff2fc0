"""DC motor + gearbox model behind the qbot report's Section 3 assumption, "speed linear in voltage"."""

import numpy as np
import pytest

from twil_control.control.dc_motor import (
    DcMotorError,
    DcMotorParams,
    motor_current,
    no_load_speed,
    stall_torque,
    steady_state_speed,
    voltage_for_speed,
    wheel_torque,
)

pytestmark = pytest.mark.kernels

P = DcMotorParams()
QBOT_WHEEL_RADIUS = 0.055


def test_no_load_speed_is_linear_in_voltage_to_1e_12():
    volts = np.linspace(-5.0, 5.0, 101)
    speeds = no_load_speed(volts)
    slope = 1.0 / (P.back_emf_constant * P.gear_ratio)  # 1.754 rad/s per V
    assert np.max(np.abs(speeds - slope * volts)) < 1e-12
    assert no_load_speed(0.0) == 0.0
    assert no_load_speed(3.0) + no_load_speed(1.5) == pytest.approx(no_load_speed(4.5), abs=1e-12)


def test_viscous_friction_lowers_the_slope_but_keeps_no_load_speed_proportional():
    lossy = DcMotorParams(gear_efficiency=0.6, friction_viscous=0.02)
    volts = np.linspace(-5.0, 5.0, 41)
    ratio = no_load_speed(volts[volts != 0], lossy) / volts[volts != 0]
    assert np.ptp(ratio) < 1e-12
    assert ratio[0] < 1.0 / (P.back_emf_constant * P.gear_ratio)


def test_a_load_torque_makes_speed_affine_not_proportional():
    load = 0.3  # N m at the wheel
    w1, w2 = steady_state_speed(2.0, load), steady_state_speed(4.0, load)
    assert w2 != pytest.approx(2.0 * w1, rel=1e-3)
    assert w2 - w1 == pytest.approx(no_load_speed(2.0), abs=1e-12)  # same slope, offset
    assert wheel_torque(4.0, w2) == pytest.approx(load, abs=1e-12)  # torque balance


def test_default_motor_drives_qbot_at_about_half_a_metre_per_second_at_5_volts():
    w = no_load_speed(5.0)
    assert w == pytest.approx(5.0 / 0.57, abs=1e-9)  # 8.77 rad/s
    assert 0.45 < w * QBOT_WHEEL_RADIUS < 0.5  # move_base max_vel_x is 0.5 m/s
    # Stall torque exceeds the torque at which a wheel slips (mu N r ~ 0.8 N m), so the
    # motors can scrub the wheels sideways in a skid-steer turn.
    assert stall_torque(5.0) == pytest.approx(2.85, abs=1e-12)
    assert stall_torque(5.0) > 1.0 * 5.9 * 9.81 / 4 * QBOT_WHEEL_RADIUS


def test_torque_sign_follows_voltage_minus_back_emf():
    w0 = no_load_speed(5.0)
    assert wheel_torque(5.0, 0.0) > 0.0
    assert wheel_torque(5.0, w0) == pytest.approx(0.0, abs=1e-12)
    assert wheel_torque(5.0, 1.2 * w0) < 0.0  # wheel overruns the motor: braking
    assert wheel_torque(-5.0, 0.0) == -wheel_torque(5.0, 0.0)
    assert wheel_torque(0.0, 2.0) < 0.0  # shorted-winding braking
    assert motor_current(5.0, 0.0) == pytest.approx(5.0, abs=1e-12)  # 5 V / 1 ohm


def test_voltage_is_clipped_and_torque_bounded_by_stall_torque():
    assert wheel_torque(12.0, 0.0) == wheel_torque(5.0, 0.0)
    assert wheel_torque(-12.0, 1.0) == wheel_torque(-5.0, 1.0)
    w0 = no_load_speed(5.0)
    volts, speeds = np.meshgrid(np.linspace(-8, 8, 33), np.linspace(-w0, w0, 33))
    tau = wheel_torque(volts, speeds)
    assert tau.shape == (33, 33)
    assert np.max(np.abs(tau)) <= 2.0 * stall_torque(5.0) + 1e-12  # worst: full reverse at +w0
    at_rest = wheel_torque(np.linspace(-8, 8, 33), 0.0)
    assert np.max(np.abs(at_rest)) == pytest.approx(stall_torque(5.0), abs=1e-12)


def test_voltage_for_speed_inverts_steady_state_speed():
    for load in (0.0, 0.25, -0.1):
        for v in (-4.0, -1.0, 0.5, 3.3):
            w = steady_state_speed(v, load)
            assert voltage_for_speed(w, load) == pytest.approx(v, abs=1e-12)
    assert voltage_for_speed(20.0) > P.max_voltage  # unreachable speed is not hidden


@pytest.mark.parametrize(
    "field, value",
    [
        ("resistance_ohm", 0.0),
        ("torque_constant", -1.0),
        ("back_emf_constant", float("nan")),
        ("gear_ratio", 0.0),
        ("gear_efficiency", 1.5),
        ("gear_efficiency", 0.0),
        ("friction_viscous", -0.1),
        ("max_voltage", float("inf")),
    ],
)
def test_invalid_parameters_raise_naming_the_field(field, value):
    with pytest.raises(ValueError, match=rf"DcMotorParams\.{field} = "):
        DcMotorParams(**{field: value})


def test_nan_inputs_are_refused():
    with pytest.raises(DcMotorError, match="voltage"):
        wheel_torque(float("nan"), 0.0)
    with pytest.raises(DcMotorError, match="wheel_speed"):
        wheel_torque(1.0, float("inf"))
