"""The tf buffer's lookups (now composed in plain floats) against homogeneous 4x4 matrices built
independently with scipy, the float transform helpers against the numpy ones bit for bit, the
float slerp against scipy's, interpolation between stamps, extrapolation errors, and a
re-parented frame."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from twil_control.control import transforms as tr
from twil_control.core.node import Master, Node
from twil_control.core.tf import TfBroadcaster, TfBuffer, TfError, transform_stamped


def _matrix(p, q) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat(q).as_matrix()
    m[:3, 3] = p
    return m


def _random_transform(rng):
    q = rng.normal(size=4)
    return rng.normal(size=3), q / np.linalg.norm(q)


def test_float_helpers_equal_the_numpy_functions_bit_for_bit():
    rng = np.random.default_rng(3)
    for _ in range(200):
        (ta, qa), (tb, qb) = _random_transform(rng), _random_transform(rng)
        t, q = tr.compose_floats(ta, qa, tb, qb)
        tn, qn = tr.compose(ta, qa, tb, qb)
        assert np.array_equal(np.array(t), tn) and np.array_equal(np.array(q), qn)
        assert tn.dtype == float and qn.dtype == float
        ti, qi = tr.inverse_floats(ta, qa)
        tin, qin = tr.inverse(ta, qa)
        assert np.array_equal(np.array(ti), tin) and np.array_equal(np.array(qi), qin)
        assert np.array_equal(tr.quat_rotate(qa, tb), np.array(tr.qrot(qa, tb)))
    # integer input still gives float arrays
    assert tr.quat_multiply([0, 0, 0, 1], [0, 0, 0, 1]).dtype == float


def test_slerp_floats_equals_scipy_slerp_on_both_branches_and_takes_the_shorter_arc():
    from scipy.spatial.transform import Slerp

    rng = np.random.default_rng(5)
    for k in range(300):
        qa = _random_transform(rng)[1]
        # every third pair nearly parallel (dot > 0.9995: the normalised linear branch)
        qb = qa + rng.normal(scale=1e-3, size=4) if k % 3 == 0 else _random_transform(rng)[1]
        qb = qb / np.linalg.norm(qb)
        if k % 2:
            qb = -qb  # the same rotation: the arc must not change
        s = rng.uniform()
        q = np.array(tr.slerp_floats(tuple(qa), tuple(qb), s))
        expected = Slerp([0.0, 1.0], Rotation.from_quat([qa, qb]))([s]).as_quat()[0]
        assert abs(np.linalg.norm(q) - 1.0) < 1e-12
        assert min(np.abs(q - expected).max(), np.abs(q + expected).max()) < 1e-9
        # the shorter arc: q lies between qa and the representative of qb nearest it
        assert np.dot(q, qa) >= min(1.0, abs(np.dot(qa, qb))) - 1e-12
    assert np.array_equal(tr.quat_slerp(qa, qb, 0.3), np.array(tr.slerp_floats(qa, qb, 0.3)))


def _buffer():
    master = Master()
    buf = TfBuffer(Node(master, "listener"))
    return master, buf, TfBroadcaster(Node(master, "talker"))


def test_a_chain_lookup_equals_the_product_of_homogeneous_matrices_to_1e_12():
    master, buf, br = _buffer()
    rng = np.random.default_rng(7)
    chain = {
        ("map", "odom"): _random_transform(rng),
        ("odom", "base_link"): _random_transform(rng),
        ("base_link", "laser"): _random_transform(rng),
        ("map", "goal"): _random_transform(rng),
    }
    for (parent, child), (p, q) in chain.items():
        br.send(transform_stamped(parent, child, 1.0, p, q))
    M = {k: _matrix(*v) for k, v in chain.items()}
    # laser in goal: X_goal_laser = inv(X_map_goal) X_map_odom X_odom_base X_base_laser
    expected = (
        np.linalg.inv(M[("map", "goal")])
        @ M[("map", "odom")]
        @ M[("odom", "base_link")]
        @ M[("base_link", "laser")]
    )
    for t in (None, 1.0):
        p, q = buf.lookup_transform("goal", "laser", t)
        assert isinstance(p, np.ndarray) and isinstance(q, np.ndarray)
        assert np.max(np.abs(_matrix(p, q) - expected)) < 1e-12
    # the reverse lookup is the inverse
    p, q = buf.lookup_transform("laser", "goal")
    assert np.max(np.abs(_matrix(p, q) @ expected - np.eye(4))) < 1e-12


def test_interpolation_between_stamps_and_extrapolation_errors():
    master, buf, br = _buffer()
    br.send(transform_stamped("odom", "base_link", 1.0, (0.0, 0.0, 0.0), tr.quat_from_yaw(0.0)))
    br.send(transform_stamped("odom", "base_link", 2.0, (1.0, 2.0, 0.0), tr.quat_from_yaw(1.0)))
    p, q = buf.lookup_transform("odom", "base_link", 1.25)
    assert np.allclose(p, [0.25, 0.5, 0.0], atol=1e-12)
    assert tr.yaw_from_quat(q) == pytest.approx(0.25, abs=1e-12)  # slerp about one axis
    assert buf.latest_common_time("odom", "base_link") == 2.0
    with pytest.raises(TfError, match="extrapolation"):
        buf.lookup_transform("odom", "base_link", 2.5)
    with pytest.raises(TfError, match="not connected"):
        buf.lookup_transform("odom", "nowhere")


def test_a_reparented_frame_is_looked_up_through_its_new_parent():
    master, buf, br = _buffer()
    br.send(transform_stamped("a", "c", 1.0, (1.0, 0.0, 0.0), tr.quat_from_yaw(0.0)))
    br.send(transform_stamped("b", "x", 1.0, (0.0, 0.0, 0.0), tr.quat_from_yaw(0.0)))
    assert np.allclose(buf.lookup_transform("a", "c")[0], [1.0, 0.0, 0.0])
    with pytest.raises(TfError):
        buf.lookup_transform("b", "c")  # c hangs from a, not b
    br.send(transform_stamped("b", "c", 2.0, (0.0, 3.0, 0.0), tr.quat_from_yaw(math.pi / 2)))
    p, q = buf.lookup_transform("b", "c")
    assert np.allclose(p, [0.0, 3.0, 0.0]) and tr.yaw_from_quat(q) == pytest.approx(math.pi / 2)
    with pytest.raises(TfError):
        buf.lookup_transform("a", "c")  # the path found before the re-parenting is gone


def test_a_leading_slash_names_the_same_frame_as_tf_strips_it():
    # an old parameter file's `global_frame: /map` (the seed's costmaps) and a goal stamped `map`
    # are one frame: stored and looked up without the slash, whichever side has it
    master, buf, br = _buffer()
    br.send(transform_stamped("/map", "odom", 1.0, (1.0, 0.0, 0.0), tr.quat_from_yaw(0.0)))
    br.send(transform_stamped("odom", "/base_link", 1.0, (0.0, 2.0, 0.0), tr.quat_from_yaw(0.5)))
    assert buf.frames() == ["base_link", "map", "odom"]
    for target, source in (("map", "base_link"), ("/map", "base_link"), ("/map", "/base_link")):
        p, q = buf.lookup_transform(target, source)
        assert np.allclose(p, [1.0, 2.0, 0.0], atol=1e-12)
        assert tr.yaw_from_quat(q) == pytest.approx(0.5, abs=1e-12)
    p, q = buf.lookup_transform("/map", "map")  # a frame in itself: the identity, with no tf at all
    assert np.allclose(p, 0.0) and np.allclose(q, [0.0, 0.0, 0.0, 1.0])
    assert buf.latest_common_time("/odom", "base_link") == 1.0
    with pytest.raises(TfError, match="not connected"):
        buf.lookup_transform("//map", "base_link")  # one slash is dropped, as tf drops one
