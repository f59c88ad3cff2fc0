"""robot_localization's ekf_localization_node against a textbook EKF (tests/ekf_reference.py) on
recorded inputs, its measurement handling (mounting rotations, differential and relative
sensors, gravity, two_d_mode, rejection), the UKF beside the EKF, and the two Jackal
configurations (the IMU's absolute yaw fused on melodic-devel, not on noetic-devel).

The recorded inputs (tests/data/ekf/husky_square_inputs.npz) are the wheel odometry and the
hector IMU of the Husky driving a square in the house (tests/data/ros1/tryout/husky_control.launch,
27 s at 50 Hz), fed with husky_control's own localization.yaml."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from ekf_reference import ReferenceEkf

from twil_control import PACKAGE_ROOT
from twil_control.core.messages import header, msg_class
from twil_control.core.node import Master
from twil_control.core.odometry_msg import odometry_msg
from twil_control.core.params import ParamError
from twil_control.localization import ekf
from twil_control.localization import kalman_measurements as km
from twil_control.localization.kalman_filter import StateEstimator
from twil_control.localization.kalman_state import matrix_from_rpy, quat_from_rpy
from twil_control.nodes.ekf_localization import EkfLocalization, UkfLocalization

pytestmark = pytest.mark.kernels

DATA = PACKAGE_ROOT / "tests" / "data"
VENDOR = DATA / "ros1" / "vendor"
HUSKY_CONFIG = VENDOR / "husky_control" / "config" / "localization.yaml"
JACKAL_MELODIC = VENDOR / "jackal_control" / "config" / "robot_localization.yaml"
JACKAL_NOETIC = VENDOR / "jackal_control" / "noetic-devel" / "robot_localization.yaml"


def _yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def _node(config, cls=EkfLocalization, **extra):
    master = Master()
    params = yaml.safe_load(config.read_text()) if not isinstance(config, dict) else dict(config)
    params.update(extra)
    for key, value in params.items():
        master.params.set(f"/ekf_localization/{key}", value)
    node = cls(master, "ekf_localization", "/")
    out = []
    master.bus.subscribe("/odometry/filtered", "nav_msgs/Odometry", out.append, node="/test")
    return master, node, out


def _vec(x, y, z):
    return msg_class("geometry_msgs/Vector3")(x=float(x), y=float(y), z=float(z))


def _imu(t, frame, quat, rates, accel, cov_o, cov_w, cov_a):
    q = msg_class("geometry_msgs/Quaternion")(
        x=float(quat[0]), y=float(quat[1]), z=float(quat[2]), w=float(quat[3])
    )
    return msg_class("sensor_msgs/Imu")(
        header=header(frame, t),
        orientation=q,
        orientation_covariance=np.asarray(cov_o, dtype=float),
        angular_velocity=_vec(*rates),
        angular_velocity_covariance=np.asarray(cov_w, dtype=float),
        linear_acceleration=_vec(*accel),
        linear_acceleration_covariance=np.asarray(cov_a, dtype=float),
    )


def _odom(t, twist6, cov36, frame="odom", child="base_link"):
    return odometry_msg(t, frame, child, (0, 0, 0), (0, 0, 0, 1), twist6[:3], twist6[3:], np.zeros(36), cov36)


def _recorded():
    with np.load(DATA / "ekf" / "husky_square_inputs.npz") as npz:
        d = {key: npz[key] for key in npz.files}
    cov = {
        "orientation": d["imu_orientation_covariance"],
        "angular_velocity": d["imu_angular_velocity_covariance"],
        "acceleration": d["imu_linear_acceleration_covariance"],
    }
    events = [(row[0], 0, k) for k, row in enumerate(d["odom"])] + [
        (row[0], 1, k) for k, row in enumerate(d["imu"])
    ]
    return d, cov, sorted(events)


def _replay(master, d, cov, events, on_tick=None):
    """Publish the recorded messages at their stamps, odometry before IMU at equal stamps."""
    odom_pub = master.bus.advertise("/husky_velocity_controller/odom", "nav_msgs/Odometry", node="/test")
    imu_pub = master.bus.advertise("/imu/data", "sensor_msgs/Imu", node="/test")
    for t, kind, k in events:
        master.spin_until(t - 1e-9)
        master.clock.set(t)
        if kind == 0:
            odom_pub.publish(_odom(t, d["odom"][k, 1:7], d["odom_twist_covariance"]))
        else:
            row = d["imu"][k]
            imu_pub.publish(
                _imu(
                    t,
                    "base_link",
                    row[1:5],
                    row[5:8],
                    row[8:11],
                    cov["orientation"],
                    cov["angular_velocity"],
                    cov["acceleration"],
                )
            )
    master.spin_until(events[-1][0] + 0.021)


def _reference_run(d, cov, events, config: dict, frequency: float):
    """The reference filter on the same messages, fused at each tick of `frequency` Hz (the
    node's timer: tick k + 1 at tick k plus the period, in floating point)."""
    ref = ReferenceEkf(two_d=config.get("two_d_mode", False))
    imu_config = np.array(config["imu0_config"], dtype=bool)
    odom_config = np.array(config["odom0_config"], dtype=bool)
    period = 1.0 / frequency
    pending, ticks, out = list(events), [], []
    t_tick = period
    while pending or t_tick <= events[-1][0] + 0.02 + 1e-9:
        while pending and pending[0][0] <= t_tick:
            t, kind, k = pending.pop(0)
            if t <= 0.0:
                continue  # stamps at or before the last set_pose (0) are ignored
            if kind == 0:
                ref.odometry_twist(t, d["odom"][k, 1:7], d["odom_twist_covariance"], odom_config)
            else:
                row = d["imu"][k]
                ref.imu(
                    "imu0", t, row[1:5], row[5:8], cov, imu_config, config.get("imu0_differential", False)
                )
        ref.predict_to(t_tick)
        if ref.initialized:
            ticks.append(t_tick)
            out.append(ref.x.copy())
        t_tick = t_tick + period
    return np.array(ticks), np.array(out)


def test_the_node_on_recorded_husky_inputs_matches_a_textbook_ekf():
    config = yaml.safe_load(HUSKY_CONFIG.read_text())
    d, cov, events = _recorded()
    events = [e for e in events if e[0] <= 10.0]  # a side, a quarter turn, most of a side
    master, _, out = _node(HUSKY_CONFIG)
    _replay(master, d, cov, events)
    ticks, ref = _reference_run(d, cov, events, config, config["frequency"])
    assert len(out) == len(ref) >= 500  # 10 s at 50 Hz
    compared = 0
    worst = np.zeros(4)
    for t, x, m in zip(ticks, ref, out):
        assert m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 == pytest.approx(t, abs=1e-8)
        p, tw = m.pose.pose, m.twist.twist
        mine = np.array([p.position.x, p.position.y, _yaw(p.orientation), tw.angular.z])
        theirs = np.array([x[0], x[1], x[5], x[11]])
        diff = np.abs(mine - theirs)
        diff[2] = abs(math.remainder(mine[2] - theirs[2], math.tau))
        worst = np.maximum(worst, diff)
        compared += 1
    # the same model and equations in independent code agree to rounding: the reference's
    # Jacobian by central differences is good to ~1e-9, and the differential IMU's yaw rates
    # (noise 0.35 rad/s, variance 1e-6 as robot_localization computes it) are fused with a gain
    # near 1, which passes such differences on to the rate (measured 4.6e-5 rad/s at most)
    assert worst[:3].max() < 1e-5, f"x, y, yaw worst differences {worst[:3]}"
    assert worst[3] < 1e-3, f"vyaw worst difference {worst[3]}"
    # and it tracks the Husky's true heading on that square (the wheel odometry does not)
    truth = d["truth"][d["truth"][:, 0] <= 10.0]
    true_yaw = np.unwrap(2 * np.arctan2(truth[:, 3], truth[:, 4])) - 2 * math.atan2(truth[0, 3], truth[0, 4])
    ekf_yaw = np.interp(truth[:, 0], ticks, np.unwrap(ref[:, 5]))
    assert np.abs(ekf_yaw - true_yaw).max() < 0.05


def test_ukf_agrees_with_the_ekf_on_the_recorded_inputs():
    d, cov, events = _recorded()
    runs = {}
    for cls in (EkfLocalization, UkfLocalization):
        master, _, out = _node(HUSKY_CONFIG, cls)
        _replay(master, d, cov, events[:600])  # the first 12 s: a side and a quarter turn
        runs[cls.kind] = np.array(
            [(m.pose.pose.position.x, m.pose.pose.position.y, _yaw(m.pose.pose.orientation)) for m in out]
        )
    e, u = runs["ekf"], runs["ukf"]
    assert len(e) == len(u) > 290
    # the same measurements through sigma points instead of a Jacobian. robot_localization's UKF
    # corrects first with the predicted sigma points, which carry no process noise, so it gains
    # less from the wheel speeds than the EKF: 9 cm shorter after 3 m (measured), the same heading
    assert np.abs(e[:, :2] - u[:, :2]).max() < 0.12
    assert np.abs(e[:, :2] - u[:, :2]).max() > 0.01  # and not by accident the EKF itself
    assert np.abs(np.remainder(e[:, 2] - u[:, 2] + math.pi, math.tau) - math.pi).max() < 0.01


def test_transfer_jacobian_is_the_derivative_of_the_motion_model():
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = rng.normal(size=15) * 0.6
        dt = 0.05
        j = ekf.transfer_jacobian(x, dt, ekf.transfer_function(x, dt))
        numeric = np.zeros((15, 15))
        for i in range(15):
            e = np.zeros(15)
            e[i] = 1e-6
            numeric[:, i] = (
                ekf.transfer_function(x + e, dt) @ (x + e) - ekf.transfer_function(x - e, dt) @ (x - e)
            ) / 2e-6
        assert np.abs(j - numeric).max() < 1e-8


def test_an_imu_mounted_sideways_measures_the_base_roll_as_its_pitch():
    # IMU turned 90 degrees about z on the base: configured to measure roll only
    config = np.zeros(15, dtype=bool)
    config[3] = True
    mount = (matrix_from_rpy(0.0, 0.0, math.pi / 2), np.zeros(3))
    m = km.Measurement("imu0_pose", 1.0)
    cov = np.diag([0, 0, 0, 0.01, 0.02, 0.03])
    ok = km.prepare_pose(
        m,
        (matrix_from_rpy(0.1, 0.0, math.pi / 2 + 0.3), np.zeros(3)),
        cov,
        config,
        mount,
        None,
        km.PoseSensorMemory(),
        0.02,
        False,
        False,
        True,
        np.zeros(15),
        False,
    )
    assert ok
    # the mounting's yaw turns the update vector: the IMU's roll axis is the base's pitch axis
    assert list(np.flatnonzero(m.update)) == [4]
    # the mounting's yaw (pi/2) is removed from the measured yaw, and (roll, pitch) turned by it
    assert m.z[5] == pytest.approx(0.3, abs=1e-9)
    assert (m.z[3], m.z[4]) == pytest.approx((0.0, 0.1), abs=1e-9)
    assert np.diag(m.covariance)[3:6] == pytest.approx([0.02, 0.01, 0.03])


def test_a_twist_sensor_ahead_of_the_base_sees_the_turn_as_sideways_speed():
    config = np.zeros(15, dtype=bool)
    config[6:12] = True
    m = km.Measurement("twist0", 1.0)
    state = np.zeros(15)
    state[11] = 0.5  # turning at 0.5 rad/s
    km.prepare_twist(
        m,
        np.array([1.0, 0.0, 0.0]),
        np.zeros(3),
        np.eye(6) * 0.01,
        config,
        (np.eye(3), np.array([0.4, 0.0, 0.0])),
        state,
        False,
    )
    # robot_localization adds origin x state rates: (0.4, 0, 0) x (0, 0, 0.5) = (0, -0.2, 0)
    assert m.z[6:9] == pytest.approx([1.0, -0.2, 0.0])


def test_differential_and_relative_poses():
    config = np.zeros(15, dtype=bool)
    config[[0, 1, 5]] = True
    memory = km.PoseSensorMemory()
    cov = np.eye(6) * 0.01
    first = km.Measurement("pose0", 1.0)
    assert not km.prepare_pose(
        first,
        (matrix_from_rpy(0, 0, 0.2), np.array([1.0, 2.0, 0.0])),
        cov,
        config,
        km.IDENTITY,
        None,
        memory,
        0.0,
        True,
        False,
        False,
        np.zeros(15),
        False,
    )
    second = km.Measurement("pose0", 1.5)
    # moved 0.5 m along its heading (0.2 rad) and turned 0.1 rad in 0.5 s
    moved = np.array([1.0 + 0.5 * math.cos(0.2), 2.0 + 0.5 * math.sin(0.2), 0.0])
    assert km.prepare_pose(
        second,
        (matrix_from_rpy(0, 0, 0.3), moved),
        cov,
        config,
        km.IDENTITY,
        None,
        memory,
        0.5,
        True,
        False,
        False,
        np.zeros(15),
        False,
    )
    assert list(np.flatnonzero(second.update)) == [6, 7, 11]
    assert second.z[[6, 7, 11]] == pytest.approx([1.0, 0.0, 0.2])
    assert second.covariance[6, 6] == pytest.approx((0.01 + 0.01) * 0.5)
    # relative: the first pose is the origin
    memory = km.PoseSensorMemory()
    for t, pose in (
        (0.0, (matrix_from_rpy(0, 0, 1.0), np.array([5.0, 5.0, 0.0]))),
        (1.0, (matrix_from_rpy(0, 0, 1.5), np.array([5.0, 6.0, 0.0]))),
    ):
        m = km.Measurement("pose0", t)
        km.prepare_pose(
            m, pose, cov, config, km.IDENTITY, None, memory, 1.0, False, True, False, np.zeros(15), False
        )
    assert m.z[[0, 1, 5]] == pytest.approx([math.sin(1.0), math.cos(1.0), 0.5])


def test_gravity_is_removed_through_the_attitude_and_two_d_mode_zeroes_the_rest():
    config = np.zeros(15, dtype=bool)
    config[12:15] = True
    m = km.Measurement("imu0_acceleration", 1.0)
    tilt = matrix_from_rpy(0.2, 0.0, 0.0)
    at_rest = tilt.T @ np.array([0.0, 0.0, 9.80665])  # what an accelerometer at rest reads
    km.prepare_acceleration(
        m,
        at_rest + np.array([0.5, 0.0, 0.0]),
        np.eye(3) * 1e-4,
        config,
        km.IDENTITY,
        np.zeros(15),
        np.zeros(3),
        9.80665,
        tilt,
        False,
        True,
    )
    assert m.z[12:15] == pytest.approx([0.5, 0.0, 0.0], abs=1e-9)
    assert all(m.update[[2, 3, 4, 8, 9, 10, 14]]) and m.covariance[14, 14] == 1e-6


def test_a_measurement_beyond_the_rejection_threshold_is_not_fused():
    f = StateEstimator()
    first = km.Measurement("pose0", 0.1)
    first.update[0], first.covariance[0, 0] = True, 0.01
    f.process_measurement(first)
    far = km.Measurement("pose0", 0.1, rejection_threshold=3.0)
    far.z[0], far.update[0], far.covariance[0, 0] = 10.0, True, 0.01
    f.process_measurement(far)
    assert f.state[0] == 0.0
    near = km.Measurement("pose0", 0.1, rejection_threshold=3.0)
    near.z[0], near.update[0], near.covariance[0, 0] = 0.1, True, 0.01
    f.process_measurement(near)
    assert 0.0 < f.state[0] < 0.1


@pytest.mark.parametrize(
    ("config", "fuses_absolute_yaw"),
    [(JACKAL_MELODIC, True), (JACKAL_NOETIC, False)],
    ids=["melodic", "noetic"],
)
def test_jackal_configurations_fuse_the_imu_yaw_or_not(config, fuses_absolute_yaw):
    # the Jackal at rest, its IMU reporting an absolute heading of 0.5 rad (the world's east is
    # where it was switched on); the wheel odometry says it does not turn
    master, _, out = _node(config)
    odom_pub = master.bus.advertise("/jackal_velocity_controller/odom", "nav_msgs/Odometry", node="/test")
    imu_pub = master.bus.advertise("/imu/data", "sensor_msgs/Imu", node="/test")
    q = quat_from_rpy(0.0, 0.0, 0.5)
    cov_o = np.diag([1e-6, 1e-6, 2.5e-5]).reshape(9)
    for k in range(1, 251):
        t = k * 0.02
        master.spin_until(t - 1e-9)
        master.clock.set(t)
        odom_pub.publish(_odom(t, np.zeros(6), np.diag([1e-3, 1e-3, 1e-3, 1e6, 1e6, 0.03]).reshape(36)))
        imu_pub.publish(
            _imu(
                t,
                "base_link",
                q,
                (0, 0, 0),
                (0, 0, 9.8),
                cov_o,
                np.eye(3).reshape(9) * 2.5e-5,
                np.eye(3).reshape(9) * 2.5e-5,
            )
        )
    master.spin_until(5.05)
    yaw = _yaw(out[-1].pose.pose.orientation)
    if fuses_absolute_yaw:  # melodic-devel: imu0_config's yaw is true, not differential
        assert yaw == pytest.approx(0.5, abs=1e-3)
    else:  # noetic-devel: yaw false; only the rates, which are zero
        assert yaw == pytest.approx(0.0, abs=1e-3)


def test_frames_that_are_not_unique_are_refused():
    with pytest.raises(ParamError, match="must be unique"):
        _node(HUSKY_CONFIG, odom_frame="base_link")
    with pytest.raises(ParamError, match="odom0_config"):
        _node({"odom0": "odom", "odom0_config": [1, 0]})
