"""The quintic segment and the second-order hold between reference samples."""

import numpy as np
import pytest

from twil_control.control.trajectory import held_reference, quintic

pytestmark = pytest.mark.kernels


def test_quintic_meets_its_boundary_conditions_and_derivatives():
    q0, q1, T = np.array([0.0, -1.0]), np.array([1.5, 2.0]), 2.0
    for t, q, qd, qdd in ((0.0, q0, 0, 0), (T, q1, 0, 0), (-1.0, q0, 0, 0), (5.0, q1, 0, 0)):
        p, v, a = quintic(q0, q1, T, t)
        np.testing.assert_allclose(p, q, atol=1e-12)
        np.testing.assert_allclose(v, qd, atol=1e-12)
        np.testing.assert_allclose(a, qdd, atol=1e-12)
    # halfway: halfway there, at the peak speed 15/8 dq/T, zero acceleration
    p, v, a = quintic(q0, q1, T, T / 2)
    np.testing.assert_allclose(p, (q0 + q1) / 2, atol=1e-12)
    np.testing.assert_allclose(v, 15 / 8 * (q1 - q0) / T, atol=1e-12)
    np.testing.assert_allclose(a, 0.0, atol=1e-12)
    # velocity and acceleration are the derivatives of position (central differences)
    h = 1e-6
    for t in (0.3, 0.77, 1.6):
        dp = (quintic(q0, q1, T, t + h)[0] - quintic(q0, q1, T, t - h)[0]) / (2 * h)
        dv = (quintic(q0, q1, T, t + h)[1] - quintic(q0, q1, T, t - h)[1]) / (2 * h)
        np.testing.assert_allclose(quintic(q0, q1, T, t)[1], dp, rtol=1e-6)
        np.testing.assert_allclose(quintic(q0, q1, T, t)[2], dv, rtol=1e-6, atol=1e-9)
    with pytest.raises(ValueError, match="duration"):
        quintic(q0, q1, 0.0, 0.1)


def test_second_order_hold_between_100_hz_samples_of_a_quintic_is_within_2_microradians():
    q0, q1, T = np.zeros(7), np.full(7, 1.5), 2.0
    worst = 0.0
    for k in range(200):
        ts = k * 0.01
        q, qd, qdd = quintic(q0, q1, T, ts)
        for dt in (0.001, 0.005, 0.0099):
            qh, _, _ = held_reference(q, qd, qdd, dt, 0.1)
            worst = max(worst, float(np.abs(qh - quintic(q0, q1, T, ts + dt)[0]).max()))
    # bound jerk dt^3 / 6 with the quintic's peak jerk 60 dq / T^3 = 11.25 rad/s^3
    assert worst <= 11.25 * 0.0099**3 / 6 + 1e-12
    assert worst < 2e-6


def test_hold_stops_after_the_timeout_and_never_extrapolates_backwards():
    q, qd, qdd = np.array([1.0, -2.0]), np.array([0.5, 0.25]), np.array([2.0, -4.0])
    timeout = 0.1
    # inside the timeout: q + qd dt + qdd dt^2 / 2, qd + qdd dt, qdd
    q_r, qd_r, qdd_r = held_reference(q, qd, qdd, 0.05, timeout)
    np.testing.assert_allclose(q_r, q + 0.05 * qd + 0.5 * 0.05**2 * qdd, rtol=1e-15)
    np.testing.assert_allclose(qd_r, qd + 0.05 * qdd, rtol=1e-15)
    assert np.array_equal(qdd_r, qdd)
    # after it: still at the position reached at the timeout
    q_r, qd_r, qdd_r = held_reference(q, qd, qdd, 3.0, timeout)
    np.testing.assert_allclose(q_r, held_reference(q, qd, qdd, timeout, timeout)[0], rtol=1e-15)
    assert np.array_equal(qd_r, [0.0, 0.0]) and np.array_equal(qdd_r, [0.0, 0.0])
    # a sample stamped in the future is held at itself; scalars and per-sample ages broadcast
    assert held_reference(1.0, 0.5, 2.0, -0.01, timeout) == (1.0, 0.5, 2.0)
    ages = np.array([[0.0], [0.05], [1.0]])
    q_r, qd_r, _ = held_reference(q, qd, qdd, ages, timeout)
    assert q_r.shape == (3, 2) and np.array_equal(qd_r[2], [0.0, 0.0])


def test_segment_chain_starts_each_segment_where_the_previous_left_the_reference():
    from twil_control.control.trajectory import SegmentChain

    chain = SegmentChain([(1.0, [1.0], 2.0), (2.0, [3.0], 0.0), (2.5, [0.0], 1.0)])
    assert chain.sample(1.5) is None  # not started: no measured position yet
    chain.start_from([0.0])
    assert chain.sample(0.5) is None and chain.index(0.5) is None
    k, q, qd, qdd = chain.sample(1.5)
    assert k == 0 and q == pytest.approx(quintic([0.0], [1.0], 2.0, 0.5)[0])
    # segment 1 (a step) interrupts segment 0 halfway: the reference jumps to 3, at rest
    k, q, qd, qdd = chain.sample(2.2)
    assert k == 1 and list(q) == [3.0] and not qd.any() and not qdd.any()
    # segment 2 starts from the step's target
    k, q, _, _ = chain.sample(2.5)
    assert k == 2 and q == pytest.approx([3.0])
    assert chain.sample(10.0)[1] == pytest.approx([0.0])
    with pytest.raises(ValueError, match="increasing"):
        SegmentChain([(1.0, [0.0], 1.0), (1.0, [1.0], 1.0)])


def test_a_joint_program_names_the_file_and_segment_of_a_mistake(tmp_path):
    from twil_control.nodes.joint_program import ProgramError
    from twil_control.nodes.joint_trajectory_reference import load_program

    path = tmp_path / "p.yaml"
    for text, message in (
        ("- {time: 1, positions: [0, 0], duration: -1}", r"segment 0: duration must be >= 0 s"),
        ("- {time: 1, positions: [0]}", r"segment 0: positions must be 2 finite numbers"),
        (
            "- {time: 1, positions: [0, 0]}\n- {time: 0.5, positions: [0, 0]}",
            r"segment 1: time must be .* increasing",
        ),
        ("- {time: 1, position: [0, 0]}", r"segment 0 must be a mapping with keys"),
    ):
        path.write_text(text)
        with pytest.raises(ProgramError, match=rf"{path}: {message}"):
            load_program(path, 2)
    path.write_text("- {time: 1, positions: [0, 0], duration: 0}\n- {time: 2, positions: [1, 1]}")
    chain = load_program(path, 2)
    assert [d for _, _, d in chain.segments] == [0.0, 3.0]  # 3 s by default
