"""The compiled EKF (localization/ekf.py) against the same maths in plain numpy
(support/ekf_numpy.py): prediction and correction on random states, covariances and
measurements, with angles to wrap, partial and empty update vectors, NaN and infinite entries,
floored variances and the Mahalanobis gate; and the compiled twist preparation
(kalman_measurements.py) against numpy's products."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import ekf_numpy as reference

from twil_control.localization import ekf
from twil_control.localization import kalman_measurements as km
from twil_control.localization.kalman_state import matrix_from_rpy

pytestmark = pytest.mark.kernels

#: compiled and numpy results differ only by the order of floating-point sums
TOLERANCE = 1e-12


def random_state(rng: np.random.Generator) -> np.ndarray:
    x = rng.normal(size=15) * 2.0
    x[3:6] = rng.uniform(-3.0 * math.pi, 3.0 * math.pi, size=3)  # wrapped by the filter
    x[4] = rng.uniform(-1.3, 1.3)  # pitch away from the model's +-pi/2 singularity
    return x


def random_covariance(rng: np.random.Generator, size: int = 15) -> np.ndarray:
    a = rng.normal(size=(size, size))
    return a @ a.T / size + np.diag(rng.uniform(0.01, 1.0, size=size))


def test_prediction_matches_numpy():
    rng = np.random.default_rng(32)
    for _ in range(200):
        x, p = random_state(rng), random_covariance(rng)
        q, dt = random_covariance(rng), float(rng.uniform(1e-3, 0.2))
        f = ekf.transfer_function(x, dt)
        np.testing.assert_allclose(f, reference.transfer_function(x, dt), rtol=0, atol=TOLERANCE)
        np.testing.assert_allclose(
            ekf.transfer_jacobian(x, dt, f), reference.transfer_jacobian(x, dt, f), rtol=0, atol=TOLERANCE
        )
        got_x, got_p = ekf.predict(x, p, dt, q)
        want_x, want_p = reference.predict(x, p, dt, q)
        assert np.abs(got_x[3:6]).max() <= math.pi
        np.testing.assert_allclose(got_x, want_x, rtol=TOLERANCE, atol=TOLERANCE)
        np.testing.assert_allclose(got_p, want_p, rtol=TOLERANCE, atol=TOLERANCE)


def random_measurement(rng: np.random.Generator, x: np.ndarray):
    """(z, R, update): a random subset of variables (maybe none), some NaN or infinite, angles
    a few turns from the state's, some variances zero or negative (floored at 1e-9 as |r|)."""
    update = rng.random(15) < rng.uniform(0.0, 1.0)
    z = x + rng.normal(size=15) * 0.3
    z[3:6] += 2.0 * math.pi * rng.integers(-2, 3, size=3)
    bad = rng.random(15) < 0.1
    z[bad] = rng.choice([math.nan, math.inf, -math.inf], size=int(bad.sum()))
    r = random_covariance(rng) * 0.1
    odd = rng.random(15) < 0.2
    r[odd, odd] = rng.choice([0.0, -0.05, 1e-12], size=int(odd.sum()))
    return z, r, update


def test_correction_matches_numpy_with_its_gate_nan_entries_and_partial_updates():
    rng = np.random.default_rng(33)
    outcomes = {"accepted": 0, "gated": 0, "nothing to fuse": 0, "non-finite skipped": 0}
    for _ in range(400):
        x, p = random_state(rng), random_covariance(rng)
        z, r, update = random_measurement(rng, x)
        threshold = float(rng.choice([math.inf, rng.uniform(0.1, 3.0)]))
        got = ekf.correct(x, p, z, r, update, threshold)
        want = reference.correct(x, p, z, r, update, threshold)
        assert got[2] == want[2]
        np.testing.assert_allclose(got[0], want[0], rtol=TOLERANCE, atol=TOLERANCE)
        np.testing.assert_allclose(got[1], want[1], rtol=TOLERANCE, atol=TOLERANCE)
        fusable = bool((update & np.isfinite(z)).any())
        outcomes["nothing to fuse"] += not fusable
        outcomes["non-finite skipped"] += bool(got[2] and (update & ~np.isfinite(z)).any())
        outcomes["accepted"] += bool(got[2])
        outcomes["gated"] += fusable and not got[2]
    assert min(outcomes.values()) >= 10, outcomes


def test_correction_without_a_threshold_and_on_fortran_ordered_matrices():
    rng = np.random.default_rng(34)
    x, p = random_state(rng), random_covariance(rng)
    z, r, _ = random_measurement(rng, x)
    z = np.where(np.isfinite(z), z, 0.0)
    update = np.ones(15, dtype=bool)
    got_x, got_p, accepted = ekf.correct(x, np.asfortranarray(p), z, np.asfortranarray(r), update)
    want_x, want_p, _ = reference.correct(x, p, z, r, update)
    assert accepted
    np.testing.assert_allclose(got_x, want_x, rtol=TOLERANCE, atol=TOLERANCE)
    np.testing.assert_allclose(got_p, want_p, rtol=TOLERANCE, atol=TOLERANCE)


def test_twist_preparation_matches_numpy_rotations_offsets_and_masks():
    """kalman_measurements' compiled twist and covariance rotation against numpy's products: a
    sensor turned and offset from the base, masks turned with it (a quarter turn moves vx's flag
    to vy), two_d_mode's zeroed variables, a NaN variance spreading through the rotation."""
    rng = np.random.default_rng(35)
    two_d = [2, 3, 4, 8, 9, 10, 14]
    for k in range(100):
        angles = rng.uniform(-math.pi, math.pi, size=3) if k % 2 else (0.0, 0.0, math.pi / 2 * (k % 4))
        rot, origin = matrix_from_rpy(*angles), rng.normal(size=3)
        linear, angular, state = rng.normal(size=3), rng.normal(size=3), rng.normal(size=15)
        cov6 = random_covariance(rng, 6)
        if k % 10 == 0:
            cov6[1, 1] = math.nan
        config = rng.random(15) < 0.5
        two_d_mode = bool(k % 3 == 0)
        m = km.Measurement("twist", 0.0)
        km.prepare_twist(m, linear, angular, cov6, config, (rot, origin), state, two_d_mode)
        b = np.zeros((6, 6))
        b[:3, :3] = b[3:, 3:] = rot
        want_z = np.concatenate([rot @ linear + np.cross(origin, state[9:12]), rot @ angular])
        want_cov = b @ cov6 @ b.T
        want_update = np.zeros(15, dtype=bool)
        for part in (slice(6, 9), slice(9, 12)):
            scaled = rot * config[part]
            want_update[part] = (scaled * scaled).sum(axis=1) >= 1e-12
        if two_d_mode:
            want_z[[2, 3, 4]] = 0.0
            want_cov[[2, 3, 4], [2, 3, 4]] = 1e-6
            want_update[two_d] = True
        np.testing.assert_allclose(m.z[6:12], want_z, rtol=0, atol=TOLERANCE)
        np.testing.assert_allclose(m.covariance[6:12, 6:12], want_cov, rtol=0, atol=TOLERANCE)
        np.testing.assert_array_equal(m.update, want_update)
        if two_d_mode:
            assert m.covariance[14, 14] == 1e-6 and m.z[14] == 0.0
        if k % 10 == 0:
            assert np.isnan(m.covariance[6:12, 6:12]).any()
